#!/bin/bash
# up.sh DIR [--kwok] [--pods] : control plane on 127.0.0.1 — etcd, kube-apiserver, kube-controller-manager,
# kube-scheduler — with its state, logs, PKI and kubeconfig in DIR. With --kwok also a kwok controller and
# a fake node "kwok-node-0" (kwok runs nothing: every pod turns Running then Succeeded).
# With --pods (a real node follows: up-real.sh) pods must reach the apiserver through its Service
# (kubernetes.default, 10.0.0.1:443, kube-proxy): the apiserver advertises the pod bridge's own address
# (pod_gateway in lib.sh) and so listens on every address, not only 127.0.0.1 (it allows no anonymous access).
# Ports come from the environment (ETCD_PORT ETCD_PEER_PORT APISERVER_PORT KCM_PORT SCHEDULER_PORT
# KUBELET_PORT KUBELET_HEALTHZ_PORT KWOK_PORT; defaults 2379 2380 6443 10257 10259 10250 10248 10247)
# and are recorded in DIR/ports.env for the other scripts. Binaries come from build.sh.
# Stop with down.sh DIR.
set -euo pipefail
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
D=${1:?usage: up.sh DIR [--kwok] [--pods]}; KWOK=0; PODS=0
for a in "${@:2}"; do
  case $a in --kwok) KWOK=1 ;; --pods) PODS=1 ;; *) log "up.sh: unknown option $a"; exit 2 ;; esac
done
mkdir -p "$D"; D=$(cd "$D" && pwd); mkdir -p "$D/logs"
if [ ! -f "$D/ports.env" ]; then
  load_ports "$D"
  for v in ETCD_PORT ETCD_PEER_PORT APISERVER_PORT KCM_PORT SCHEDULER_PORT KUBELET_PORT KUBELET_HEALTHZ_PORT KWOK_PORT \
           KUBE_PROXY_PORT KUBE_PROXY_METRICS_PORT DNS_READY_PORT; do
    echo "$v=${!v}"
  done > "$D/ports.env"
fi
load_ports "$D"
for b in etcd kube-apiserver kube-controller-manager kube-scheduler kubectl; do
  [ -x "$BIN/$b" ] || { log "missing $BIN/$b: run build.sh first"; exit 1; }
done
[ -f "$D/pki/ca.crt" ] || "$HERE/gen-pki.sh" "$D"
P=$D/pki; export KUBECONFIG=$D/kubeconfig
K() { "$BIN/kubectl" --kubeconfig="$D/kubeconfig" "$@"; }
t0=$(now)
fail() { log "$1"; for f in "$D"/logs/*.log; do echo "--- $f" >&2; tail -n 20 "$f" >&2; done; exit 1; }
BIND=127.0.0.1; ADVERTISE=127.0.0.1
if [ "$PODS" = 1 ]; then read -r ADVERTISE _ < <(pod_gateway); BIND=0.0.0.0; fi

"$BIN/etcd" --name=uavtest --data-dir="$D/etcd-data" \
  --listen-client-urls="http://127.0.0.1:$ETCD_PORT" --advertise-client-urls="http://127.0.0.1:$ETCD_PORT" \
  --listen-peer-urls="http://127.0.0.1:$ETCD_PEER_PORT" --initial-advertise-peer-urls="http://127.0.0.1:$ETCD_PEER_PORT" \
  --initial-cluster="uavtest=http://127.0.0.1:$ETCD_PEER_PORT" --unsafe-no-fsync --log-level=warn \
  </dev/null >"$D/logs/etcd.log" 2>&1 &
echo $! > "$D/etcd.pid"

"$BIN/kube-apiserver" --etcd-servers="http://127.0.0.1:$ETCD_PORT" \
  --bind-address="$BIND" --advertise-address="$ADVERTISE" --secure-port="$APISERVER_PORT" --anonymous-auth=false \
  --tls-cert-file="$P/apiserver.crt" --tls-private-key-file="$P/apiserver.key" \
  --client-ca-file="$P/ca.crt" --token-auth-file="$P/tokens.csv" \
  --service-account-issuer=https://kubernetes.default.svc.cluster.local \
  --service-account-key-file="$P/sa.pub" --service-account-signing-key-file="$P/sa.key" \
  --service-cluster-ip-range=$SERVICE_CIDR --authorization-mode=Node,RBAC --profiling=false \
  --kubelet-client-certificate="$P/admin.crt" --kubelet-client-key="$P/admin.key" \
  --kubelet-preferred-address-types=Hostname,InternalIP \
  </dev/null >"$D/logs/apiserver.log" 2>&1 &
echo $! > "$D/apiserver.pid"
wait_for 90 K get --raw=/readyz || fail "kube-apiserver not ready after 90 s"

"$BIN/kube-controller-manager" --kubeconfig="$D/kubeconfig" --bind-address=127.0.0.1 --secure-port="$KCM_PORT" \
  --leader-elect=false --service-account-private-key-file="$P/sa.key" --root-ca-file="$P/ca.crt" \
  --use-service-account-credentials=false --profiling=false --flex-volume-plugin-dir="$D/kcm-flexvolume" \
  </dev/null >"$D/logs/kcm.log" 2>&1 &
echo $! > "$D/kcm.pid"
"$BIN/kube-scheduler" --kubeconfig="$D/kubeconfig" --bind-address=127.0.0.1 --secure-port="$SCHEDULER_PORT" \
  --leader-elect=false --profiling=false \
  </dev/null >"$D/logs/scheduler.log" 2>&1 &
echo $! > "$D/scheduler.pid"

if [ "$KWOK" = 1 ]; then
  mkdir -p "$D/kwokhome"
  HOME=$D/kwokhome "$BIN/kwok" --kubeconfig="$D/kubeconfig" --config="$SHARE/kwok-stages.yaml" \
    --manage-nodes-with-annotation-selector=kwok.x-k8s.io/node=fake --cidr=10.244.0.0/16 --node-ip=127.0.0.1 \
    --server-address="127.0.0.1:$KWOK_PORT" \
    </dev/null >"$D/logs/kwok.log" 2>&1 &
  echo $! > "$D/kwok.pid"
  K apply -f - >/dev/null <<'EOF'
apiVersion: v1
kind: Node
metadata:
  name: kwok-node-0
  annotations: {node.alpha.kubernetes.io/ttl: "0", kwok.x-k8s.io/node: fake}
  labels: {kubernetes.io/hostname: kwok-node-0, kubernetes.io/os: linux, kubernetes.io/arch: amd64, type: kwok}
status:
  allocatable: {cpu: "32", memory: 256Gi, pods: "110"}
  capacity: {cpu: "32", memory: 256Gi, pods: "110"}
EOF
  K wait --for=condition=Ready node/kwok-node-0 --timeout=60s >/dev/null || fail "kwok node not Ready"
fi
# pods are refused until kcm's serviceaccount controller has made the namespace's default SA
wait_for 60 K get serviceaccount default -n default || fail "no default service account after 60 s"
log "control plane up in $(since "$t0")s: KUBECONFIG=$D/kubeconfig"
