#!/bin/bash
# build.sh [STEP...] : build (once) everything the e2e cluster needs, into $UAVTEST_CACHE (~/.cache/uavtest).
#   steps: k8s kube-proxy etcd kwok minio helm coredns pause debs iptables   (default: all, in that order)
# Each step is skipped when its outputs exist and its version stamp matches; each prints its duration.
# From nothing it needs only Go (>= 1.26), apt-get/dpkg-deb, and the Go module proxy + Debian mirror.
set -euo pipefail
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

mkdir -p "$BIN" "$SHARE" "$CACHE/src" "$CACHE/deb"
exec 9>"$CACHE/.build.lock"; flock 9   # concurrent test sessions share the cache: one build at a time
STEPS=("$@"); [ ${#STEPS[@]} -gt 0 ] || STEPS=(k8s kube-proxy etcd kwok minio helm coredns pause debs iptables prometheus)

# stamp_ok NAME KEY FILE... : true when every FILE exists and the stamp of NAME reads KEY
stamp_ok() {
  local name=$1 key=$2; shift 2
  [ "$(cat "$BIN/.stamp-$name" 2>/dev/null)" = "$key" ] || return 1
  for f in "$@"; do [ -e "$f" ] || return 1; done
}
stamp_set() { echo "$2" > "$BIN/.stamp-$1"; }
filesum() { cat "$@" | sha256sum | cut -c1-16; }

# wrapper module: copy go.mod/go.sum from the repo into the cache (builds never write into the repo)
wrapper() {
  local name=$1 dst=$CACHE/src/$1
  mkdir -p "$dst"
  cp "$HERE/go/$name/go.mod" "$dst/go.mod"
  if [ -f "$HERE/go/$name/go.sum" ]; then cp "$HERE/go/$name/go.sum" "$dst/go.sum"; fi
  echo "$dst"
}

build_k8s() {
  local key; key="$K8S_VERSION $(filesum "$HERE/go/k8s/go.mod" "$HERE/go/k8s/go.sum")"
  local outs=("$BIN/kube-apiserver" "$BIN/kube-controller-manager" "$BIN/kube-scheduler" "$BIN/kubelet" "$BIN/kubectl")
  if stamp_ok k8s "$key" "${outs[@]}"; then SKIPPED=1; return 0; fi
  local src minor ld
  src=$(wrapper k8s); minor=$(echo "$K8S_VERSION" | cut -d. -f2)
  # without the version ldflags the binaries say v0.0.0 and kubectl/kubelet refuse the server
  ld="-s -w -X k8s.io/component-base/version.gitVersion=$K8S_VERSION -X k8s.io/component-base/version.gitMajor=1"
  ld="$ld -X k8s.io/component-base/version.gitMinor=$minor -X k8s.io/client-go/pkg/version.gitVersion=$K8S_VERSION"
  ld="$ld -X k8s.io/component-base/version.gitTreeState=clean"
  (cd "$src" && go build -trimpath -ldflags="$ld" -o "$BIN/" tool)
  stamp_set k8s "$key"
}

# kube-proxy: a wrapper module of its own (go/kube-proxy, the same k8s.io/kubernetes version and replaces), so
# adding it left the k8s step's stamp alone; shares the Go build cache, so it mostly links (~20 s warm)
build_kube_proxy() {
  local key; key="$K8S_VERSION $(filesum "$HERE/go/kube-proxy/go.mod" "$HERE/go/kube-proxy/go.sum")"
  if stamp_ok kube-proxy "$key" "$BIN/kube-proxy"; then SKIPPED=1; return 0; fi
  local src minor ld
  src=$(wrapper kube-proxy); minor=$(echo "$K8S_VERSION" | cut -d. -f2)
  ld="-s -w -X k8s.io/component-base/version.gitVersion=$K8S_VERSION -X k8s.io/component-base/version.gitMajor=1"
  ld="$ld -X k8s.io/component-base/version.gitMinor=$minor -X k8s.io/component-base/version.gitTreeState=clean"
  (cd "$src" && go build -trimpath -ldflags="$ld" -o "$BIN/" tool)
  stamp_set kube-proxy "$key"
}

build_etcd() {
  local key; key="$ETCD_VERSION $(filesum "$HERE/go/etcd/go.mod" "$HERE/go/etcd/go.sum")"
  if stamp_ok etcd "$key" "$BIN/etcd"; then SKIPPED=1; return 0; fi
  local src; src=$(wrapper etcd)
  # go.etcd.io/etcd/server/v3 has replace directives, so `go install ...@version` is refused: wrapper module
  (cd "$src" && go build -trimpath -ldflags='-s -w' -o "$BIN/etcd" go.etcd.io/etcd/server/v3)
  stamp_set etcd "$key"
}

build_kwok() {
  if stamp_ok kwok "$KWOK_VERSION" "$BIN/kwok" "$SHARE/kwok-stages.yaml"; then SKIPPED=1; return 0; fi
  GOBIN=$BIN go install -trimpath -ldflags='-s -w' "sigs.k8s.io/kwok/cmd/kwok@$KWOK_VERSION"
  # stages: nodes become Ready and keep a heartbeat; pods go Running then Succeeded, and can be deleted
  local st=$GOMODCACHE/sigs.k8s.io/kwok@$KWOK_VERSION/kustomize/stage f
  : > "$SHARE/kwok-stages.yaml.tmp"
  for f in node/fast/node-initialize node/heartbeat/node-heartbeat pod/fast/pod-ready pod/fast/pod-complete \
           pod/fast/pod-delete; do
    { echo "---"; cat "$st/$f.yaml"; } >> "$SHARE/kwok-stages.yaml.tmp"
  done
  mv "$SHARE/kwok-stages.yaml.tmp" "$SHARE/kwok-stages.yaml"
  stamp_set kwok "$KWOK_VERSION"
}

build_minio() {
  if stamp_ok minio "$MINIO_VERSION" "$BIN/minio"; then SKIPPED=1; return 0; fi
  GOBIN=$BIN go install -trimpath -ldflags='-s -w' "github.com/minio/minio@$MINIO_VERSION"
  stamp_set minio "$MINIO_VERSION"
}

build_helm() {
  if stamp_ok helm "$HELM_VERSION" "$BIN/helm"; then SKIPPED=1; return 0; fi
  GOBIN=$BIN go install -trimpath -ldflags='-s -w' "helm.sh/helm/v3/cmd/helm@$HELM_VERSION"
  stamp_set helm "$HELM_VERSION"
}

# the cluster DNS: CoreDNS (kubernetes + forward plugins), run on the host by up-real.sh
build_coredns() {
  if stamp_ok coredns "$COREDNS_VERSION" "$BIN/coredns"; then SKIPPED=1; return 0; fi
  GOBIN=$BIN go install -trimpath -ldflags='-s -w' "github.com/coredns/coredns@$COREDNS_VERSION"
  stamp_set coredns "$COREDNS_VERSION"
}

build_pause() {
  local key; key=$(filesum "$HERE/go/pause/main.go" "$HERE/go/pause/go.mod" "$HERE/mkoci.py")
  if stamp_ok pause "$key" "$BIN/pause" "$SHARE/pause.tar"; then SKIPPED=1; return 0; fi
  (cd "$HERE/go/pause" && go build -trimpath -ldflags='-s -w' -o "$BIN/pause" .)
  local t; t=$(mktemp -d); mkdir -p "$t/root"/{dev,proc,sys,etc,tmp}; cp "$BIN/pause" "$t/root/pause"; chmod 1777 "$t/root/tmp"
  python3 "$HERE/mkoci.py" layer "$t/root" "$t/layer.tar" >/dev/null
  python3 "$HERE/mkoci.py" image --out "$SHARE/pause.tar" --name "$PAUSE_IMAGE" --entrypoint '["/pause"]' \
    "$t/layer.tar" >/dev/null
  rm -rf "$t"
  stamp_set pause "$key"
}

# containerd + runc + CNI plugins from Debian, unpacked into the cache (never installed on the host)
build_debs() {
  local key="$DEB_PACKAGES"
  if stamp_ok debs "$key" "$DEBX/usr/bin/containerd" "$DEBX/usr/sbin/runc" "$DEBX/usr/lib/cni/bridge"; then
    SKIPPED=1; return 0
  fi
  fetch_debs "$CACHE/deb/pkgs" $DEB_PACKAGES
  rm -rf "$DEBX"; mkdir -p "$DEBX"
  for f in "$CACHE"/deb/pkgs/*.deb; do dpkg-deb -x "$f" "$DEBX"; done
  stamp_set debs "$key"
}

# iptables (nft backend) + conntrack for kube-proxy, unpacked into a directory of their own (not DEBX: a
# running cluster uses DEBX, and sessions of other checkouts may re-unpack it); the Debian alternatives are
# made by hand as symlinks in $IPTX/bin (iptables -> xtables-nft-multi, ...)
build_iptables() {
  local key="$IPT_PACKAGES"
  if stamp_ok iptables "$key" "$IPTX/bin/iptables" "$IPTX/bin/conntrack"; then SKIPPED=1; return 0; fi
  fetch_debs "$CACHE/deb/ipt-pkgs" $IPT_PACKAGES
  rm -rf "$IPTX"; mkdir -p "$IPTX/bin"
  for f in "$CACHE"/deb/ipt-pkgs/*.deb; do dpkg-deb -x "$f" "$IPTX"; done
  local t v
  for t in iptables ip6tables; do
    for v in "" -save -restore; do ln -s ../usr/sbin/xtables-nft-multi "$IPTX/bin/$t$v"; done
  done
  ln -s ../usr/sbin/conntrack "$IPTX/bin/conntrack"
  stamp_set iptables "$key"
}

# Prometheus and promtool from Debian's package (the dashboard and alert rules are evaluated against it)
build_prometheus() {
  local key=prometheus
  if stamp_ok prometheus "$key" "$BIN/prometheus" "$BIN/promtool"; then SKIPPED=1; return 0; fi
  fetch_debs "$CACHE/deb/prom-pkgs" prometheus
  rm -rf "$CACHE/deb/prom"; mkdir -p "$CACHE/deb/prom"
  dpkg-deb -x "$CACHE"/deb/prom-pkgs/prometheus_*.deb "$CACHE/deb/prom"
  ln -sf "$CACHE/deb/prom/usr/bin/prometheus" "$BIN/prometheus"
  ln -sf "$CACHE/deb/prom/usr/bin/promtool" "$BIN/promtool"
  stamp_set prometheus "$key"
}

# fetch_debs DIR PKG... : apt-get download PKGs into DIR (apt-get update once if the lists lack them)
fetch_debs() {
  local dir=$1; shift
  rm -rf "$dir"; mkdir -p "$dir"
  if ! (cd "$dir" && apt-get download "$@" >/dev/null 2>&1); then
    log "apt-get download failed; running apt-get update"
    apt-get update -qq >/dev/null
    (cd "$dir" && apt-get download "$@" >/dev/null 2>&1)
  fi
}

total0=$(now)
for s in "${STEPS[@]}"; do
  declare -F "build_${s//-/_}" >/dev/null || { log "unknown step: $s"; exit 2; }
  t0=$(now); SKIPPED=0
  trap 'log "build $s: FAILED after $(since "$t0")s"' ERR
  "build_${s//-/_}"   # not in an `||` context, so `set -e` stays in force inside the step
  trap - ERR
  if [ "$SKIPPED" = 1 ]; then log "build $s: up to date ($(since "$t0")s)"; else log "build $s: built in $(since "$t0")s"; fi
done
log "build total: $(since "$total0")s (cache: $CACHE)"
