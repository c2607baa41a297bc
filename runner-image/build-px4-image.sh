#!/bin/bash
# build-px4-image.sh BUILD_DIR [OUT.tar] [--name NAME[:TAG]] [--thin]
#
# Packages a PX4 SITL build YOU made (PX4-Autopilot's build/px4_sitl_default: bin/, etc/,
# parameters.json) into an OCI image archive, without Docker. The image runs PX4 SITL (SIH) as
# instance 0, sending MAVLink to 127.0.0.1:14540: what the uavtest operator's `sitl` sidecar expects.
#   layer 1  Debian bookworm minbase (the e2e suite's cached base layer, tests/cluster/lib.sh)
#   layer 2  bc (PX4's rcS computes the speed factor with it) + the entrypoint /usr/local/bin/px4-sitl
#            (runner-image/px4-entrypoint.sh); cached
#   layer 3  the build: /opt/px4/bin, /opt/px4/etc, /opt/px4/parameters.json — made every time
# PX4's binary links libstdc++/libm/libc only: build it on Debian bookworm (or older glibc) to match.
# Writes OUT.tar (default $UAVTEST_CACHE/share/uavtest-px4-dev.tar), a self-contained archive for
# `ctr -n k8s.io images import`, `kind load image-archive` or `skopeo copy oci-archive:OUT.tar ...`.
# --thin writes the PX4 layer only, with OUT.tar.base naming the cached base image archive (layers 1+2)
# to import first (tests/cluster/import-image.sh does both). Image name default uavtest-px4:dev.
# Needs root (debootstrap, mount, chroot), apt-get (downloads bc's .deb), python3.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
. "$ROOT/tests/cluster/lib.sh"
USAGE="usage: build-px4-image.sh BUILD_DIR [OUT.tar] [--name NAME[:TAG]] [--thin]"
THIN=0; NAME=uavtest-px4:dev; ARGS=()
while [ $# -gt 0 ]; do
  case $1 in
    --thin) THIN=1 ;;
    --name) NAME=${2:?$USAGE}; shift ;;
    --name=*) NAME=${1#--name=} ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    -*) echo "$USAGE" >&2; exit 2 ;;
    *) ARGS+=("$1") ;;
  esac
  shift
done
[ ${#ARGS[@]} -ge 1 ] && [ ${#ARGS[@]} -le 2 ] || { echo "$USAGE" >&2; exit 2; }
BUILD=$(cd "${ARGS[0]}" 2>/dev/null && pwd) || { echo "BUILD_DIR ${ARGS[0]}: no such directory" >&2; exit 2; }
OUT=${ARGS[1]:-$SHARE/uavtest-px4-dev.tar}
for need in bin/px4 etc/init.d-posix/rcS; do
  [ -e "$BUILD/$need" ] || {
    echo "BUILD_DIR $BUILD has no $need: expected a PX4 SITL build (make px4_sitl_default -> build/px4_sitl_default)" >&2
    exit 2
  }
done
[ -f "$BUILD/parameters.json" ] || log "note: $BUILD has no parameters.json: PX4_HOME_LAT/LON are passed as given"
case $NAME in */*) REF=$NAME ;; *) REF=docker.io/library/$NAME ;; esac   # as containerd CRI looks it up
case ${REF##*/} in *:*) ;; *) REF=$REF:latest ;; esac

image_work_begin   # IMG, WORK, the lock (lib.sh)
mkdir -p "$(dirname "$OUT")"
ENTRY=$ROOT/runner-image/px4-entrypoint.sh

# ---------------------------------------------------------------- layer 1: debootstrap (shared)
debian_base_layer   # sets KA, A

# ---------------------------------------------------------------- layer 2: bc + entrypoint
t0=$(now)
DEBS=$CACHE/deb/px4
if ! ls "$DEBS"/bc_*.deb >/dev/null 2>&1; then
  mkdir -p "$DEBS"
  (cd "$DEBS" && { apt-get download bc >/dev/null 2>&1 || { apt-get update -qq >/dev/null; apt-get download bc >/dev/null; }; })
fi
BC_DEB=$(ls "$DEBS"/bc_*.deb | tail -n1)
PX4_RECIPE=1   # bump when the way layer 2 is made changes
KC=$(key "$KA" "$(basename "$BC_DEB")" "$(sha256sum < "$ENTRY")" "$PX4_RECIPE")
C=$IMG/px4extra-$KC
if [ -f "$C/layer.tar" ]; then
  log "image layer 2 (bc + entrypoint): cached ($(since "$t0")s)"
else
  rm -rf "$C"; mkdir -p "$WORK/extra"
  M=$WORK/extra/merged
  overlay_mount "$A/rootfs" "$WORK/extra/upper" "$WORK/extra/work" "$M"
  cp "$BC_DEB" "$M/tmp/bc.deb"
  chroot_run "$M" dpkg -i /tmp/bc.deb >/dev/null
  rm -f "$M/tmp/bc.deb"; rm -rf "$M"/usr/share/doc/* "$M"/usr/share/man/* "$M"/usr/share/info/* "$M"/var/log/*.log
  install -m 0755 "$ENTRY" "$M/usr/local/bin/px4-sitl"
  install -d -m 0777 "$M/var/lib/px4"   # the default working directory (the pod mounts an emptyDir instead)
  echo 2+2 | chroot_run "$M" bc >/dev/null
  overlay_umount "$M"
  rmdir "$M"; rm -rf "$WORK/extra/work"
  python3 "$HERE/mkoci.py" layer "$WORK/extra/upper" "$WORK/extra/layer.tar" >/dev/null
  mv "$WORK/extra" "$C"
  log "image layer 2 (bc + entrypoint): built in $(since "$t0")s"
fi

# ---------------------------------------------------------------- layer 3: the PX4 build
t0=$(now)
P=$WORK/px4/upper/opt/px4
mkdir -p "$P"
cp -a "$BUILD/bin" "$BUILD/etc" "$P/"
[ -f "$BUILD/parameters.json" ] && cp "$BUILD/parameters.json" "$P/"
chmod -R a+rX,go-w "$P"
python3 "$HERE/mkoci.py" layer "$WORK/px4/upper" "$WORK/px4/layer.tar" >/dev/null
IMAGE_CONFIG=(--env "PATH=/opt/px4/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
              --env PX4_SIM_MODEL=sihsim_quadx --env LANG=C.UTF-8 --workdir /var/lib/px4
              --entrypoint '["/usr/local/bin/px4-sitl"]')
if [ "$THIN" = 1 ]; then
  BASE_REF=docker.io/library/uavtest-px4-base:$KC
  if [ ! -f "$C/base-image.tar" ]; then   # layers 1+2 as an image of their own, made once per layer-2 key
    python3 "$HERE/mkoci.py" image --out "$C/base-image.tar.tmp" --name "$BASE_REF" "${IMAGE_CONFIG[@]}" \
      "$A/layer.tar" "$C/layer.tar" >/dev/null
    mv "$C/base-image.tar.tmp" "$C/base-image.tar"
  fi
  python3 "$HERE/mkoci.py" image --thin 2 --out "$OUT" --name "$REF" "${IMAGE_CONFIG[@]}" \
    "$A/layer.tar" "$C/layer.tar" "$WORK/px4/layer.tar" >/dev/null
  echo "$BASE_REF $C/base-image.tar" > "$OUT.base"
else
  python3 "$HERE/mkoci.py" image --out "$OUT" --name "$REF" "${IMAGE_CONFIG[@]}" \
    "$A/layer.tar" "$C/layer.tar" "$WORK/px4/layer.tar" >/dev/null
  rm -f "$OUT.base"
fi
log "image layer 3 (PX4 build $BUILD) + archive: built in $(since "$t0")s -> $OUT ($(du -h "$OUT" | cut -f1)), image $REF"
image_cache_hygiene "$A" "$C"
