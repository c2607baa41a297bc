# shellcheck shell=bash disable=SC2034
# Shared settings of the e2e cluster scripts: sourced, never run.
# Everything the harness builds or downloads lives under $UAVTEST_CACHE (default ~/.cache/uavtest).

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
CACHE=${UAVTEST_CACHE:-$HOME/.cache/uavtest}
BIN=$CACHE/bin          # built binaries (kube-*, kubectl, etcd, kwok, minio, pause)
SHARE=$CACHE/share      # kwok stages, images (OCI archives)
DEBX=$CACHE/deb/x       # Debian packages unpacked with dpkg-deb -x (containerd, runc, CNI, debootstrap)
IPTX=$CACHE/deb/ipt     # iptables + conntrack unpacked the same way (kube-proxy); bin/ holds the command names

# --- pinned versions (bump here; the version stamps then force a rebuild)
K8S_VERSION=v1.36.3
ETCD_VERSION=v3.6.16
KWOK_VERSION=v0.8.0
# github.com/minio/minio has no semver tags: a pseudo-version of master (2026-02-12), builds with Go 1.26
MINIO_VERSION=v0.0.0-20260212201848-7aac2a2c5b7c
HELM_VERSION=v3.16.4   # renders charts/uavtest in the chart tests
DEB_PACKAGES="containerd runc containernetworking-plugins"
COREDNS_VERSION=v1.14.7   # the cluster DNS (go install)
# kube-proxy's iptables mode: iptables with its libraries the host may lack, and conntrack (Debian bookworm)
IPT_PACKAGES="iptables libip4tc2 libip6tc2 libxtables12 libnftnl11 libmnl0 libnetfilter-conntrack3 libnfnetlink0 conntrack"
REAL_NODE_OWNER=/run/uavtest-real-node   # "DIR PID" of the cluster that has the host's one real node
PAUSE_IMAGE=uavtest.local/pause:1   # the pod sandbox image, built from go/pause
RUNNER_IMAGE=uavtest-runner:dev   # what pod specs say (imagePullPolicy: Never)
RUNNER_IMAGE_REF=docker.io/library/$RUNNER_IMAGE   # the same, normalised as containerd CRI looks it up
OPERATOR_IMAGE_REF=docker.io/library/uavtest-operator:dev   # the operator image (same layers, its own config)
MINIO_IMAGE_REF=uavtest.local/minio:dev   # MinIO for the chart's throwaway minio (layer 1 + the minio binary)

# Go: caches under the cache dir so a warm machine rebuilds nothing and downloads nothing
if ! command -v go >/dev/null 2>&1; then export PATH=/usr/local/go/bin:$PATH; fi
export GOPATH=$CACHE/go/path GOMODCACHE=$CACHE/go/mod GOCACHE=$CACHE/go/build
export GOFLAGS=-buildvcs=false CGO_ENABLED=${CGO_ENABLED:-0}

log() { echo "[uavtest-cluster] $*" >&2; }
now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

# wait_for SECONDS CMD... : poll CMD every 0.2 s until it succeeds; non-zero if it never did
wait_for() {
  local n=$(( $1 * 5 )); shift
  for (( i = 0; i < n; i++ )); do "$@" >/dev/null 2>&1 && return 0; sleep 0.2; done
  return 1
}

# stop_pidfile FILE... : TERM the processes named in the PID FILEs together, give them
# $UAVTEST_STOP_GRACE seconds (default 5) to exit, then KILL the rest; remove the FILEs
stop_pidfile() {
  local f p pids=() n
  for f in "$@"; do
    [ -f "$f" ] || continue
    p=$(cat "$f"); rm -f "$f"
    [ -n "$p" ] && kill "$p" 2>/dev/null && pids+=("$p")
  done
  [ ${#pids[@]} -gt 0 ] || return 0
  n=$(( ${UAVTEST_STOP_GRACE:-5} * 10 ))
  for (( i = 0; i < n; i++ )); do
    alive=0; for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && return 0
    sleep 0.1
  done
  # one may exit by itself between the check above and this KILL: that is not an error (set -e)
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  for (( i = 0; i < 50; i++ )); do
    alive=0; for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && return 0
    sleep 0.1
  done
  return 0
}

# port NAME DEFAULT : a port from the cluster dir's ports.env (written by up.sh), else env, else default
load_ports() {
  local d=$1
  # shellcheck disable=SC1091
  [ -f "$d/ports.env" ] && . "$d/ports.env"
  ETCD_PORT=${ETCD_PORT:-2379}; ETCD_PEER_PORT=${ETCD_PEER_PORT:-2380}; APISERVER_PORT=${APISERVER_PORT:-6443}
  KCM_PORT=${KCM_PORT:-10257}; SCHEDULER_PORT=${SCHEDULER_PORT:-10259}
  KUBELET_PORT=${KUBELET_PORT:-10250}; KUBELET_HEALTHZ_PORT=${KUBELET_HEALTHZ_PORT:-10248}
  KWOK_PORT=${KWOK_PORT:-10247}
  KUBE_PROXY_PORT=${KUBE_PROXY_PORT:-10256}; KUBE_PROXY_METRICS_PORT=${KUBE_PROXY_METRICS_PORT:-10249}
  DNS_READY_PORT=${DNS_READY_PORT:-8181}
}

# ------------------------------------------------------------------ image building (no Docker)
# Shared by build-runner-image.sh and runner-image/build-px4-image.sh. image_work_begin sets IMG (the
# layer cache), takes its lock and makes WORK (removed, with whatever is mounted under it, on exit).
IMAGE_SUITE=bookworm
IMAGE_BASE_PACKAGES="python3,python3-venv,ca-certificates"
IMAGE_BASE_RECIPE=1   # bump when the way the base layer is made changes

image_work_begin() {
  [ "$(id -u)" = 0 ] || { log "$(basename "$0") needs root (debootstrap, mount, chroot)"; exit 1; }
  IMG=$CACHE/image; mkdir -p "$IMG" "$SHARE"
  exec 9>"$IMG/.lock"; flock 9   # one image build at a time per cache
  WORK=$(mktemp -d "$IMG/tmp.XXXXXX")
  trap image_work_cleanup EXIT
  trap 'exit 130' INT TERM
}
image_work_cleanup() {   # unmount whatever is still mounted under WORK (overlays; debootstrap's proc/sys if it died)
  grep -F " $WORK/" /proc/self/mountinfo | awk '{print $5}' | sort -r | while read -r m; do umount -l "$m"; done || true
  rm -rf "$WORK"
}
key() { printf '%s\n' "$@" | sha256sum | cut -c1-16; }

# chroot_run ROOT CMD... : run CMD in ROOT with a clean environment (no host PIP_* settings leak in)
chroot_run() {
  local root=$1; shift
  env -i PATH="${IMAGE_PATH:-/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin}" HOME=/root LANG=C.UTF-8 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 chroot "$root" "$@"
}

# overlay_mount LOWER(S) UPPER WORK MERGED
overlay_mount() {
  mkdir -p "$2" "$3" "$4"
  mount -t overlay overlay -o "lowerdir=$1,upperdir=$2,workdir=$3" "$4"
}
overlay_umount() { umount "$1"; }

# debian_base_layer : layer 1 of every image the suite builds: Debian bookworm `debootstrap --variant=minbase`
# + python3, python3-venv, ca-certificates, cached as $IMG/base-<key>/{rootfs,layer.tar}. Sets KA (its key)
# and A (its folder). Needs image_work_begin first.
debian_base_layer() {
  local t0 DB MIRROR KEYRING GPG R
  t0=$(now)
  KA=$(key "$IMAGE_SUITE" "$IMAGE_BASE_PACKAGES" "$IMAGE_BASE_RECIPE")
  A=$IMG/base-$KA
  if [ -f "$A/layer.tar" ] && [ -d "$A/rootfs/usr" ]; then
    log "image layer 1 (debian $IMAGE_SUITE + python3): cached ($(since "$t0")s)"
    return 0
  fi
  DB=$CACHE/deb/debootstrap
  if [ ! -x "$DB/x/usr/sbin/debootstrap" ]; then
    rm -rf "$DB"; mkdir -p "$DB/pkgs" "$DB/x"
    (cd "$DB/pkgs" && { apt-get download debootstrap >/dev/null 2>&1 || { apt-get update -qq >/dev/null; apt-get download debootstrap >/dev/null; }; })
    dpkg-deb -x "$DB"/pkgs/debootstrap_*.deb "$DB/x"
  fi
  if ! command -v wget >/dev/null; then   # debootstrap downloads with wget
    log "installing wget (debootstrap needs it)"
    apt-get install -y -qq --no-install-recommends wget >/dev/null 2>&1 || \
      { apt-get update -qq >/dev/null; apt-get install -y -qq --no-install-recommends wget >/dev/null; }
  fi
  MIRROR=${UAVTEST_DEBIAN_MIRROR:-}
  if [ -z "$MIRROR" ]; then   # the host's own Debian mirror, else deb.debian.org
    MIRROR=$(cat /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '/^URIs:/ {print $2}' | grep -v security | head -n1 || true)
    [ -n "$MIRROR" ] || MIRROR=$(awk '/^deb / && !/security/ {print $2; exit}' /etc/apt/sources.list 2>/dev/null || true)
    MIRROR=${MIRROR:-http://deb.debian.org/debian}
  fi
  KEYRING=/usr/share/keyrings/debian-archive-keyring.gpg
  GPG=(--keyring="$KEYRING"); [ -f "$KEYRING" ] || GPG=(--no-check-gpg)
  rm -rf "$A"; mkdir -p "$WORK/base"
  DEBOOTSTRAP_DIR=$DB/x/usr/share/debootstrap "$DB/x/usr/sbin/debootstrap" --variant=minbase \
    --include="$IMAGE_BASE_PACKAGES" "${GPG[@]}" "$IMAGE_SUITE" "$WORK/base/rootfs" "$MIRROR" > "$WORK/debootstrap.log" 2>&1 \
    || { tail -n 30 "$WORK/debootstrap.log" >&2; tail -n 30 "$WORK/base/rootfs/debootstrap/debootstrap.log" 2>/dev/null >&2; exit 1; }
  R=$WORK/base/rootfs
  rm -rf "$R"/var/cache/apt/archives/*.deb "$R"/var/lib/apt/lists/* "$R"/usr/share/doc/* "$R"/usr/share/man/* \
         "$R"/usr/share/info/* "$R"/var/log/*.log "$R"/var/cache/debconf/*-old "$R"/var/lib/dpkg/*-old
  : > "$R/etc/resolv.conf"
  echo uavtest-runner > "$R/etc/hostname"
  python3 "$HERE/mkoci.py" layer --empty dev --empty proc --empty sys --empty run "$R" "$WORK/base/layer.tar" >/dev/null
  mv "$WORK/base" "$A"
  log "image layer 1 (debian $IMAGE_SUITE + python3): built in $(since "$t0")s"
}

# image_cache_hygiene DIR... : mark DIRs used; layers no build used for 3 days go
image_cache_hygiene() {
  local d
  for d in "$@"; do touch "$d/.used"; done
  for d in "$IMG"/base-* "$IMG"/deps-* "$IMG"/buildenv-* "$IMG"/px4extra-* "$IMG"/minio-*; do
    [ -d "$d" ] && [ -z "$(find "$d/.used" -mtime -3 2>/dev/null)" ] && rm -rf "$d"
  done
  true
}

# pod_gateway [SUBNET] : the bridge's own address in the pod subnet (its first host) and the prefix length,
# e.g. "10.244.7.1 24": pods' default route, where the apiserver and the cluster DNS are reached from pods
pod_gateway() {
  python3 -c 'import ipaddress, sys; n = ipaddress.ip_network(sys.argv[1]); print(next(n.hosts()), n.prefixlen)' \
    "${1:-${UAVTEST_POD_SUBNET:-10.244.7.0/24}}"
}
SERVICE_CIDR=10.0.0.0/24   # ClusterIPs; the apiserver's Service "kubernetes" is 10.0.0.1
CLUSTER_DOMAIN=cluster.local
