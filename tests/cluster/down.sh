#!/bin/bash
# down.sh DIR [--purge] : stop what up.sh DIR started (kwok, scheduler, kcm, apiserver, etcd), by PID file.
# --purge also removes DIR. For a cluster with a real node run down-real.sh instead (it calls this).
set -euo pipefail
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
D=${1:?usage: down.sh DIR [--purge]}
[ -d "$D" ] || exit 0
D=$(cd "$D" && pwd)
# a throwaway cluster: no need for an orderly shutdown, all at once with a short grace period
UAVTEST_STOP_GRACE=${UAVTEST_STOP_GRACE:-1} \
  stop_pidfile "$D/kopf.pid" "$D/kwok.pid" "$D/scheduler.pid" "$D/kcm.pid" "$D/apiserver.pid" "$D/etcd.pid"
# kube-controller-manager of older runs (before --flex-volume-plugin-dir) made this on the host
for d in /usr/libexec/kubernetes/kubelet-plugins/volume/exec /usr/libexec/kubernetes/kubelet-plugins/volume \
         /usr/libexec/kubernetes/kubelet-plugins /usr/libexec/kubernetes; do rmdir "$d" 2>/dev/null || true; done
if [ "${2:-}" = --purge ]; then rm -rf "$D"; fi
log "control plane down: $D"
