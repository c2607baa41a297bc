#!/bin/bash
# gen-pki.sh DIR : CA, apiserver serving cert, admin client cert (system:masters), service-account key pair,
# token file and DIR/kubeconfig (server https://127.0.0.1:$APISERVER_PORT). Uses openssl only.
set -euo pipefail
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
D=$(cd "${1:?usage: gen-pki.sh DIR}" && pwd); load_ports "$D"
mkdir -p "$D/pki"; cd "$D/pki"
q() { "$@" 2>/dev/null; }
q openssl req -x509 -newkey rsa:2048 -nodes -keyout ca.key -out ca.crt -days 3650 -subj "/CN=uavtest-e2e-ca"
q openssl req -newkey rsa:2048 -nodes -keyout apiserver.key -out apiserver.csr -subj "/CN=kube-apiserver"
q openssl x509 -req -in apiserver.csr -CA ca.crt -CAkey ca.key -CAcreateserial -out apiserver.crt -days 3650 \
  -extfile <(printf '%s\n' "subjectAltName=IP:127.0.0.1,IP:10.0.0.1,DNS:localhost,DNS:kubernetes,DNS:kubernetes.default,DNS:kubernetes.default.svc" "extendedKeyUsage=serverAuth")
q openssl req -newkey rsa:2048 -nodes -keyout admin.key -out admin.csr -subj "/O=system:masters/CN=uavtest-admin"
q openssl x509 -req -in admin.csr -CA ca.crt -CAkey ca.key -CAcreateserial -out admin.crt -days 3650 \
  -extfile <(printf '%s\n' "extendedKeyUsage=clientAuth")
q openssl genrsa -out sa.key 2048
q openssl rsa -in sa.key -pubout -out sa.pub
echo "$(openssl rand -hex 16),uavtest-admin,uavtest-admin,system:masters" > tokens.csv
chmod 600 ./*.key tokens.csv
cat > "$D/kubeconfig" <<KC
apiVersion: v1
kind: Config
clusters:
- name: uavtest-e2e
  cluster:
    server: https://127.0.0.1:${APISERVER_PORT}
    certificate-authority: $D/pki/ca.crt
users:
- name: uavtest-admin
  user:
    client-certificate: $D/pki/admin.crt
    client-key: $D/pki/admin.key
contexts:
- name: uavtest-e2e
  context: {cluster: uavtest-e2e, user: uavtest-admin, namespace: default}
current-context: uavtest-e2e
KC
chmod 600 "$D/kubeconfig"
