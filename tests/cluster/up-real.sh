#!/bin/bash
# up-real.sh DIR : after `up.sh DIR`, add a REAL node named "localhost": containerd + runc + CNI bridge
# (Debian packages unpacked by build.sh) and a kubelet. Pods really run; images must be imported first
# (`ctr -n k8s.io images import`) and used with imagePullPolicy: Never.
# containerd's root (images, unpacked layers) persists across clusters in $UAVTEST_CONTAINERD_ROOT (default
# $UAVTEST_CACHE/containerd-root), so importing an image whose layers are there already is quick; its
# state (tasks, mounts, sockets) lives in DIR. Containers never outlive a cluster (removed on both ends).
# Needs root. One real node per host at a time (kubelet and containerd hard-code a few host paths).
# Env: UAVTEST_BRIDGE (default uavtest0), UAVTEST_POD_SUBNET (default 10.244.7.0/24).
# The pod network is a real one: the bridge has the subnet's first address (pods' default route), kube-proxy
# (iptables mode, on the host) gives Services their ClusterIPs (10.0.0.0/24; the apiserver is 10.0.0.1:443 when
# up.sh had --pods), and CoreDNS on the bridge address is the cluster DNS (kubelet clusterDNS, cluster.local).
# IPv4 forwarding is switched on while the node runs (down-real.sh puts the old value back).
# Stop with down-real.sh DIR, which also undoes what kubelet/containerd changed on the host.
set -euo pipefail
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
D=$(cd "${1:?usage: up-real.sh DIR}" && pwd); load_ports "$D"
[ -f "$D/kubeconfig" ] && [ -f "$D/apiserver.pid" ] || { log "run up.sh $D first"; exit 1; }
[ "$(id -u)" = 0 ] || { log "up-real.sh needs root (containerd, runc, mounts, network namespaces)"; exit 1; }
for f in "$DEBX/usr/bin/containerd" "$DEBX/usr/sbin/runc" "$DEBX/usr/lib/cni/bridge" "$BIN/kubelet" "$SHARE/pause.tar" \
         "$BIN/kube-proxy" "$BIN/coredns" "$IPTX/bin/iptables"; do
  [ -e "$f" ] || { log "missing $f: run build.sh first"; exit 1; }
done
BR=${UAVTEST_BRIDGE:-uavtest0}; SUBNET=${UAVTEST_POD_SUBNET:-10.244.7.0/24}
read -r GW PREFIX < <(pod_gateway "$SUBNET")
C=$D/ctr; KL=$D/kubelet; CROOT=${UAVTEST_CONTAINERD_ROOT:-$CACHE/containerd-root}
export PATH=$DEBX/usr/bin:$DEBX/usr/sbin:$PATH   # containerd finds containerd-shim-runc-v2 on PATH
K() { "$BIN/kubectl" --kubeconfig="$D/kubeconfig" "$@"; }
t0=$(now)
fail() { log "$1"; for f in "$D"/logs/{containerd,kubelet,kube-proxy,coredns}.log; do echo "--- $f" >&2; tail -n 30 "$f" >&2; done; exit 1; }

# one real node per host: test sessions sharing the machine take turns (UAVTEST_REAL_NODE_WAIT seconds at most)
owner_alive() {   # owner_alive DIR UP_REAL_PID : is that cluster's up-real.sh, containerd or kubelet running?
  local d=$1 p                # (a live PID whose command line names DIR: PIDs get reused)
  [ -d "$d" ] || return 1
  for p in "$2" $(cat "$d/kubelet.pid" "$d/containerd.pid" 2>/dev/null); do
    [[ $(tr '\0' ' ' 2>/dev/null < "/proc/$p/cmdline") == *"$d"* ]] && return 0
  done
  return 1
}
claim_node() {
  local lockdir=/run/lock; [ -d $lockdir ] || lockdir=/run
  exec 8<"$lockdir"; flock 8   # short critical section; locks the directory, so no lock file is left behind
  local other="" opid=""
  [ -f "$REAL_NODE_OWNER" ] && read -r other opid < "$REAL_NODE_OWNER"
  if [ -n "$other" ] && [ "$other" != "$D" ] && owner_alive "$other" "$opid"; then exec 8<&-; return 1; fi
  # any kubelet at all (another cache's cluster, the host's own) also holds the host
  if pgrep -x kubelet >/dev/null; then exec 8<&-; return 1; fi
  echo "$D $$" > "$REAL_NODE_OWNER"; exec 8<&-
}
waited=0
until claim_node; do
  [ $waited = 0 ] && log "another real-node cluster runs on this host ($(cat "$REAL_NODE_OWNER")): waiting"
  (( waited += 2 )); sleep 2
  (( waited < ${UAVTEST_REAL_NODE_WAIT:-900} )) || { log "gave up waiting for the real node after ${waited}s"; exit 1; }
done

# what down-real.sh must restore or leave alone: kubelet tunes these sysctls on start
{
  echo "BRIDGE=$BR"
  echo "CONTAINERD_ROOT=$CROOT"
  for s in vm/overcommit_memory vm/panic_on_oom kernel/panic kernel/panic_on_oops kernel/keys/root_maxkeys \
           kernel/keys/root_maxbytes net/ipv4/ip_forward; do
    [ -r "/proc/sys/$s" ] && echo "SYSCTL $s $(cat "/proc/sys/$s")"
  done
} > "$D/host-state.txt"

mkdir -p "$C/cni" "$C/ipam" "$KL" "$D/logs"
cat > "$C/config.toml" <<EOF
version = 2
root = "$CROOT"
state = "$C/state"
# opt would create /opt/containerd on the host; the others are snapshotters we do not use
disabled_plugins = ["io.containerd.internal.v1.opt", "io.containerd.snapshotter.v1.btrfs",
  "io.containerd.snapshotter.v1.zfs", "io.containerd.snapshotter.v1.devmapper", "io.containerd.snapshotter.v1.aufs",
  "io.containerd.tracing.processor.v1.otlp"]
[grpc]
  address = "$C/containerd.sock"
[ttrpc]
  address = "$C/containerd.sock.ttrpc"
[metrics]
  address = ""
[plugins."io.containerd.grpc.v1.cri"]
  sandbox_image = "$PAUSE_IMAGE"
  stream_server_address = "127.0.0.1"
  stream_server_port = "0"
  # the VM lacks CAP_SYS_RESOURCE for negative oom_score_adj
  restrict_oom_score_adj = true
  disable_apparmor = true
  [plugins."io.containerd.grpc.v1.cri".containerd]
    snapshotter = "overlayfs"
    default_runtime_name = "runc"
    [plugins."io.containerd.grpc.v1.cri".containerd.runtimes.runc]
      runtime_type = "io.containerd.runc.v2"
      [plugins."io.containerd.grpc.v1.cri".containerd.runtimes.runc.options]
        BinaryName = "$DEBX/usr/sbin/runc"
        Root = "$C/runc-root"
        SystemdCgroup = false
  [plugins."io.containerd.grpc.v1.cri".cni]
    bin_dir = "$DEBX/usr/lib/cni"
    conf_dir = "$C/cni"
EOF
cat > "$C/cni/10-uavtest.conflist" <<EOF
{"cniVersion": "1.0.0", "name": "uavtest",
 "plugins": [
  {"type": "bridge", "bridge": "$BR", "isGateway": true, "ipMasq": false, "hairpinMode": true,
   "ipam": {"type": "host-local", "dataDir": "$C/ipam", "ranges": [[{"subnet": "$SUBNET", "gateway": "$GW"}]],
            "routes": [{"dst": "0.0.0.0/0"}]}},
  {"type": "loopback"}]}
EOF
cat > "$KL/config.yaml" <<EOF
apiVersion: kubelet.config.k8s.io/v1beta1
kind: KubeletConfiguration
address: 127.0.0.1
port: $KUBELET_PORT
readOnlyPort: 0
healthzBindAddress: 127.0.0.1
healthzPort: $KUBELET_HEALTHZ_PORT
containerRuntimeEndpoint: unix://$C/containerd.sock
cgroupDriver: cgroupfs
failCgroupV1: false
failSwapOn: false
cgroupsPerQOS: false
enforceNodeAllocatable: []
podLogsDir: $KL/pod-logs
volumePluginDir: $KL/volume-plugins
authentication:
  anonymous: {enabled: false}
  webhook: {enabled: false}
  x509: {clientCAFile: $D/pki/ca.crt}
authorization: {mode: AlwaysAllow}
serializeImagePulls: false
imageGCHighThresholdPercent: 100
imageGCLowThresholdPercent: 99
evictionHard: {memory.available: "100Mi", nodefs.available: "1%", imagefs.available: "1%"}
registerNode: true
resolvConf: ""
clusterDNS: [$GW]
clusterDomain: $CLUSTER_DOMAIN
EOF

# the bridge, with its address, before anything listens on it (the CNI bridge plugin adopts it)
ip link show "$BR" >/dev/null 2>&1 || ip link add "$BR" type bridge
ip addr replace "$GW/$PREFIX" dev "$BR"; ip link set "$BR" up
echo 1 > /proc/sys/net/ipv4/ip_forward   # pod -> Service -> pod goes through the host

CTR=("$DEBX/usr/bin/ctr" --address "$C/containerd.sock" -n k8s.io)
start_containerd() {
  mkdir -p "$CROOT"
  "$DEBX/usr/bin/containerd" --config "$C/config.toml" </dev/null >>"$D/logs/containerd.log" 2>&1 &
  echo $! > "$D/containerd.pid"
  wait_for 30 "${CTR[@]}" version
}
if ! start_containerd; then   # a broken persistent root (a run killed mid-write): start afresh once
  log "containerd did not start; wiping its root $CROOT and retrying"
  stop_pidfile "$D/containerd.pid"; rm -rf "$CROOT"
  start_containerd || fail "containerd did not answer in 30 s"
fi
# containers of a cluster that died without down-real.sh: remove them (and their snapshots) before kubelet
for c in $("${CTR[@]}" containers ls -q); do "${CTR[@]}" containers rm "$c" >/dev/null 2>&1 || true; done
"${CTR[@]}" images import "$SHARE/pause.tar" >/dev/null

"$BIN/kubelet" --config="$KL/config.yaml" --kubeconfig="$D/kubeconfig" --root-dir="$KL/root" \
  --cert-dir="$KL/pki" --hostname-override=localhost </dev/null >"$D/logs/kubelet.log" 2>&1 &
echo $! > "$D/kubelet.pid"
node_ready() { [ "$(K get node localhost -o 'jsonpath={.status.conditions[?(@.type=="Ready")].status}')" = True ]; }
wait_for 90 node_ready || fail "node localhost not Ready after 90 s"

# kube-proxy, iptables mode, with iptables from build.sh (nft backend). No conntrack sysctls are changed
# (maxPerCore 0, timeouts 0) and no localhost NodePorts (no route_localnet): the host keeps its settings.
cat > "$D/kube-proxy.yaml" <<EOF
apiVersion: kubeproxy.config.k8s.io/v1alpha1
kind: KubeProxyConfiguration
clientConnection: {kubeconfig: $D/kubeconfig}
hostnameOverride: localhost
mode: iptables
clusterCIDR: $SUBNET
bindAddress: 127.0.0.1
healthzBindAddress: 127.0.0.1:$KUBE_PROXY_PORT
metricsBindAddress: 127.0.0.1:$KUBE_PROXY_METRICS_PORT
conntrack: {maxPerCore: 0, min: 0, tcpEstablishedTimeout: 0s, tcpCloseWaitTimeout: 0s}
iptables: {localhostNodePorts: false}
EOF
env PATH="$IPTX/bin:$PATH" LD_LIBRARY_PATH="$IPTX/usr/lib/x86_64-linux-gnu" \
  XTABLES_LIBDIR="$IPTX/usr/lib/x86_64-linux-gnu/xtables" \
  "$BIN/kube-proxy" --config="$D/kube-proxy.yaml" </dev/null >"$D/logs/kube-proxy.log" 2>&1 &
echo $! > "$D/kube-proxy.pid"
wait_for 60 curl -sf "http://127.0.0.1:$KUBE_PROXY_PORT/healthz" || fail "kube-proxy not healthy after 60 s"

# the cluster DNS: CoreDNS on the bridge address, answering from the apiserver (Services, pods)
cat > "$D/Corefile" <<EOF
.:53 {
    bind $GW
    errors
    ready 127.0.0.1:$DNS_READY_PORT
    kubernetes $CLUSTER_DOMAIN in-addr.arpa ip6.arpa {
        kubeconfig $D/kubeconfig
        pods insecure
        fallthrough in-addr.arpa ip6.arpa
    }
    forward . /etc/resolv.conf
    cache 30
    loop
}
EOF
"$BIN/coredns" -conf "$D/Corefile" </dev/null >"$D/logs/coredns.log" 2>&1 &
echo $! > "$D/coredns.pid"
wait_for 60 curl -sf "http://127.0.0.1:$DNS_READY_PORT/ready" || fail "CoreDNS not ready after 60 s"
log "real node up in $(since "$t0")s: $(K get node localhost --no-headers)"
