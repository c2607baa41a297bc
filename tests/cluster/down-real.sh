#!/bin/bash
# down-real.sh DIR [--purge] : stop the real node of up-real.sh DIR and then the control plane (down.sh), and
# undo what kubelet/containerd did to the host: container processes and shims, mounts under DIR, network
# namespaces, the CNI bridge, the k8s.io cgroups, the few hard-coded host paths, the sysctls kubelet tuned,
# kube-proxy's iptables rules (`kube-proxy --cleanup`), IPv4 forwarding.
# Host-wide clean-up happens only if this cluster held the host's real node (see up-real.sh), so it never
# touches another session's running node. Safe to run twice, or after a failed up-real.sh.
set -uo pipefail   # no -e: clean up as much as possible, whatever fails
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
D=${1:?usage: down-real.sh DIR [--purge]}
[ -d "$D" ] || exit 0
D=$(cd "$D" && pwd); load_ports "$D"
C=$D/ctr
CTR=("$DEBX/usr/bin/ctr" --address "$C/containerd.sock" -n k8s.io)
ctr_ok() { [ -S "$C/containerd.sock" ] && timeout 5 "${CTR[@]}" version >/dev/null 2>&1; }
no_tasks() { [ -z "$(timeout 5 "${CTR[@]}" tasks ls -q 2>/dev/null)" ]; }
t0=$(now)
# the host's real node stays ours (see up-real.sh) until this script has finished cleaning up the host:
# the owner record names this script's PID meanwhile, and is removed only at the very end
lockdir=/run/lock; [ -d $lockdir ] || lockdir=/run
exec 8<"$lockdir"; flock 8
owner=""; [ -f "$REAL_NODE_OWNER" ] && read -r owner _ < "$REAL_NODE_OWNER"
OWNED=0; { [ "$owner" = "$D" ] || [ -z "$owner" ]; } && [ -f "$D/host-state.txt" ] && OWNED=1
if [ "$OWNED" = 1 ] && [ -z "$owner" ]; then   # no record: ours only if no other kubelet runs
  for p in $(pgrep -x kubelet || true); do
    [[ $(tr '\0' ' ' 2>/dev/null < "/proc/$p/cmdline") == *"$D/"* ]] || OWNED=0
  done
fi
[ "$OWNED" = 1 ] && echo "$D $$" > "$REAL_NODE_OWNER"
exec 8<&-

# 1-2. a throwaway cluster: nothing to drain. Stop whatever makes or runs pods (kcm's Job controller, the
#      scheduler, kubelet) at once, then kill every container through containerd (the netns, mounts and cgroups
#      they leave are removed below)
UAVTEST_STOP_GRACE=0 stop_pidfile "$D/kcm.pid" "$D/scheduler.pid" "$D/kubelet.pid" "$D/kube-proxy.pid" "$D/coredns.pid"
# 3. kill the tasks, remove the containers, stop containerd
if ctr_ok; then
  for t in $(timeout 5 "${CTR[@]}" tasks ls -q 2>/dev/null); do
    timeout 5 "${CTR[@]}" tasks kill -a -s SIGKILL "$t" >/dev/null 2>&1
  done
  for t in $(timeout 5 "${CTR[@]}" tasks ls -q 2>/dev/null); do
    timeout 5 "${CTR[@]}" tasks rm -f "$t" >/dev/null 2>&1
  done
  wait_for 10 no_tasks
  # containerd's root persists (images): leave no container records or rw snapshots in it
  for c in $(timeout 5 "${CTR[@]}" containers ls -q 2>/dev/null); do
    timeout 10 "${CTR[@]}" containers rm "$c" >/dev/null 2>&1
    echo "$c" >> "$D/containers-removed.txt"
  done
fi
stop_pidfile "$D/containerd.pid"
CROOT=$(sed -n 's/^CONTAINERD_ROOT=//p' "$D/host-state.txt" 2>/dev/null)
# 4. leftovers by PID: container inits recorded in containerd's state dir, then shims (their command line names
#    our containerd socket, which lives in DIR)
for f in "$C"/state/io.containerd.runtime.v2.task/*/*/init.pid; do
  [ -f "$f" ] && kill -9 "$(cat "$f")" 2>/dev/null
done
for p in /proc/[0-9]*; do
  cmd=$(tr '\0' ' ' 2>/dev/null < "$p/cmdline")
  [[ $cmd == *"-address $C/containerd.sock"* ]] && kill -9 "${p#/proc/}" 2>/dev/null
done
sleep 0.2
# 5. mounts under DIR (and containerd's root), deepest first; CRI's per-container files in the root (if ours)
for r in "$D" ${CROOT:+"$CROOT"}; do
  grep -F " $r/" /proc/self/mountinfo | awk '{print $5}' | sort -r | while read -r m; do umount -l "$m" 2>/dev/null; done
done
[ "$OWNED" = 1 ] && [ -n "$CROOT" ] && \
  rm -rf "$CROOT"/io.containerd.grpc.v1.cri/sandboxes/* "$CROOT"/io.containerd.grpc.v1.cri/containers/*
# 6. the control plane
"$HERE/down.sh" "$D"

if [ "$OWNED" = 1 ]; then
  # 7. network: pod netns no process uses any more (ours; CRI names them cni-*), and the CNI bridge
  live=" $(for p in /proc/[0-9]*; do stat -L -c %i "$p/ns/net" 2>/dev/null; done | sort -u | tr '\n' ' ') "
  for n in /run/netns/cni-*; do
    [ -e "$n" ] || continue
    ino=$(stat -L -c %i "$n" 2>/dev/null) || continue
    [[ $live == *" $ino "* ]] && continue
    umount -l "$n" 2>/dev/null; rm -f "$n"
  done
  # kube-proxy's chains and rules (iptables nft backend), the way kube-proxy itself removes them
  if [ -x "$BIN/kube-proxy" ] && [ -x "$IPTX/bin/iptables" ]; then
    env PATH="$IPTX/bin:$PATH" LD_LIBRARY_PATH="$IPTX/usr/lib/x86_64-linux-gnu" \
      XTABLES_LIBDIR="$IPTX/usr/lib/x86_64-linux-gnu/xtables" bash -c '
        timeout 30 "$1" --cleanup
        # --cleanup leaves the (empty) filter chain KUBE-FIREWALL and its jumps behind
        for c in INPUT OUTPUT; do while iptables -w 5 -D "$c" -j KUBE-FIREWALL 2>/dev/null; do :; done; done
        iptables -w 5 -F KUBE-FIREWALL 2>/dev/null; iptables -w 5 -X KUBE-FIREWALL 2>/dev/null; true
      ' _ "$BIN/kube-proxy" >>"$D/logs/kube-proxy.log" 2>&1
  fi
  BR=$(sed -n 's/^BRIDGE=//p' "$D/host-state.txt" 2>/dev/null)
  [ -n "$BR" ] && ip link del "$BR" 2>/dev/null
  # 8. host paths kubelet / containerd 1.6 / libcni hard-code: remove what this run left, dirs only if empty
  for l in /var/log/containers/*.log; do
    [ -L "$l" ] && case "$(readlink "$l")" in "$D"/*) rm -f "$l" ;; esac
  done
  rm -f /var/lib/kubelet/device-plugins/kubelet.sock /var/lib/cni/results/uavtest-*
  # libcni's cached results of our sandboxes (no CNI DEL ran: their netns went away with the sandboxes)
  if [ -f "$D/containers-removed.txt" ]; then
    while read -r c; do rm -f /var/lib/cni/results/*-"$c"-*; done < "$D/containers-removed.txt"
  fi
  for d in /var/lib/kubelet/device-plugins /var/lib/kubelet /var/log/containers /var/log/pods /var/lib/cni/results \
           /var/lib/cni /run/containerd/runc/k8s.io /run/containerd/runc /run/containerd/s /run/containerd/fifo \
           /run/containerd/io.containerd.runtime.v2.task/k8s.io /run/containerd/io.containerd.runtime.v2.task \
           /run/containerd /run/netns; do
    rmdir "$d" 2>/dev/null
  done
  # 9. the pod cgroups containerd made (cgroup v1: <controller>/k8s.io, v2: /k8s.io), deepest first, once empty
  for c in /sys/fs/cgroup/*/k8s.io /sys/fs/cgroup/k8s.io; do
    [ -d "$c" ] && find "$c" -depth -type d -exec rmdir {} \; 2>/dev/null
  done
  # 10. sysctls kubelet changed
  while read -r kind key val; do
    [ "$kind" = SYSCTL ] && [ "$(cat "/proc/sys/$key" 2>/dev/null)" != "$val" ] && echo "$val" > "/proc/sys/$key"
  done < "$D/host-state.txt"
  exec 8<"$lockdir"; flock 8
  owner=""; [ -f "$REAL_NODE_OWNER" ] && read -r owner _ < "$REAL_NODE_OWNER"
  [ "$owner" = "$D" ] && rm -f "$REAL_NODE_OWNER"
  exec 8<&-
fi
if [ "${2:-}" = --purge ]; then rm -rf "$D"; fi
log "real node down in $(since "$t0")s"
exit 0
