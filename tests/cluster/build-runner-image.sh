#!/bin/bash
# build-runner-image.sh REPO_ROOT [OUT.tar] : the runner OCI image "uavtest-runner:dev", without Docker, and
# beside OUT.tar the operator image "uavtest-operator:dev" (uavtest-operator-dev.tar: the same layers, the root
# Dockerfile's config) and, when build.sh made MinIO, a MinIO image "uavtest.local/minio:dev" (minio.tar).
#   layer 1  Debian bookworm rootfs: debootstrap --variant=minbase + python3, python3-venv
#            (cached under $UAVTEST_CACHE/image, keyed by the package list)
#   layer 2  a venv /opt/uavtest holding the project's dependencies (wheels for CPython 3.11 manylinux,
#            fetched with pip on the host; cached, keyed by layer 1 + pyproject's dependency list)
#   layer 3  the project's wheel, built from REPO_ROOT's working tree (tracked + untracked, not ignored
#            files) — rebuilt every time; `uavtest` is on PATH (/usr/local/bin/uavtest -> /opt/uavtest/bin)
# Layers 2 and 3 are made with an overlay mount + chroot, so pip runs with the image's own python.
# Writes OUT.tar (default $UAVTEST_CACHE/share/uavtest-runner-dev.tar), an OCI archive for
# `ctr -n k8s.io images import`. By default OUT.tar is THIN (~2 MB: the project layer only) and OUT.tar.base
# names the cached base image archive (layers 1+2, "uavtest-runner-base:<key>") that must be imported first:
# import-image.sh does both, and imports the base only when containerd lacks it. With --full, OUT.tar is a
# self-contained archive (~850 MB) instead. Needs root (debootstrap, mount, chroot).
set -euo pipefail
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
FULL=0; ARGS=()
for a in "$@"; do if [ "$a" = --full ]; then FULL=1; else ARGS+=("$a"); fi; done
REPO=$(cd "${ARGS[0]:?usage: build-runner-image.sh REPO_ROOT [OUT.tar] [--full]}" && pwd)
OUT=${ARGS[1]:-$SHARE/uavtest-runner-dev.tar}
IMAGE_PATH=/opt/uavtest/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
image_work_begin   # IMG, WORK, the lock; key, chroot_run, overlay_mount from lib.sh
mkdir -p "$(dirname "$OUT")"
PYVER=3.11      # bookworm's python3
VENV=/opt/uavtest

# ---------------------------------------------------------------- layer 1: debootstrap (lib.sh)
debian_base_layer   # sets KA, A

# ---------------------------------------------------------------- layer 2: dependencies in a venv
t0=$(now)
REQS=$(python3 - "$REPO/pyproject.toml" <<'EOF'
import sys, tomllib
print("\n".join(tomllib.load(open(sys.argv[1], "rb"))["project"]["dependencies"]))
EOF
)
KB=$(key "$KA" "$PYVER" "$REQS")
B=$IMG/deps-$KB
if [ -f "$B/layer.tar" ] && [ -d "$B/upper$VENV" ]; then
  log "image layer 2 (dependencies venv): cached ($(since "$t0")s)"
else
  rm -rf "$B"; mkdir -p "$WORK/deps/wheels"
  echo "$REQS" > "$WORK/deps/wheels/requirements.txt"
  # binary wheels for the image's interpreter (CPython 3.11, glibc 2.36), whatever the host's python is
  env -u PIP_FIND_LINKS python3 -m pip download --quiet --disable-pip-version-check --only-binary=:all: \
    --python-version "$PYVER" --implementation cp --abi "cp${PYVER/./}" --abi abi3 --abi none \
    --platform manylinux_2_36_x86_64 --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux2014_x86_64 --platform manylinux_2_5_x86_64 --platform manylinux1_x86_64 --platform any \
    -d "$WORK/deps/wheels" -r "$WORK/deps/wheels/requirements.txt"
  M=$WORK/deps/merged
  overlay_mount "$A/rootfs" "$WORK/deps/upper" "$WORK/deps/work" "$M"
  cp -a "$WORK/deps/wheels" "$M/tmp/wheels"
  chroot_run "$M" /usr/bin/python3 -m venv "$VENV"
  chroot_run "$M" "$VENV/bin/pip" install --quiet --no-cache-dir --no-index --find-links /tmp/wheels \
    -r /tmp/wheels/requirements.txt
  ln -s "$VENV/bin/uavtest" "$M/usr/local/bin/uavtest"   # dangling until layer 3 installs the project
  rm -rf "$M/tmp/wheels" "$M/root/.cache"
  overlay_umount "$M"
  rmdir "$M"; rm -rf "$WORK/deps/work" "$WORK/deps/wheels"
  python3 "$HERE/mkoci.py" layer "$WORK/deps/upper" "$WORK/deps/layer.tar" >/dev/null
  mv "$WORK/deps" "$B"
  log "image layer 2 (dependencies venv): built in $(since "$t0")s"
fi

# ---------------------------------------------------------------- layer 3: the project, from the work tree
t0=$(now)
mkdir -p "$WORK/proj/src" "$WORK/proj/dist"
(cd "$REPO" && git ls-files -z --cached --others --exclude-standard | while IFS= read -r -d '' f; do
   [ -e "$f" ] && printf '%s\0' "$f"; done | tar --null -T - -cf -) | tar -xf - -C "$WORK/proj/src"
# a cached venv with the project's build-system requirements: no isolated build env to download every time
BUILD_REQS=$(python3 - "$REPO/pyproject.toml" <<'EOF'
import sys, tomllib
print("\n".join(tomllib.load(open(sys.argv[1], "rb"))["build-system"]["requires"]))
EOF
)
BE=$IMG/buildenv-$(key "$BUILD_REQS" "$(python3 -V 2>&1)")
if [ ! -f "$BE/.complete" ]; then
  rm -rf "$BE"; python3 -m venv "$BE"
  echo "$BUILD_REQS" > "$WORK/build-reqs.txt"
  "$BE/bin/python" -m pip install --quiet --disable-pip-version-check -r "$WORK/build-reqs.txt"
  touch "$BE/.complete"
fi
"$BE/bin/python" -m pip wheel --quiet --disable-pip-version-check --no-deps --no-build-isolation \
  -w "$WORK/proj/dist" "$WORK/proj/src"
M=$WORK/proj/merged
overlay_mount "$B/upper:$A/rootfs" "$WORK/proj/upper" "$WORK/proj/work" "$M"
WHL=$(cd "$WORK/proj/dist" && ls uavtest-*.whl)
mkdir -p "$M/tmp/dist"; cp "$WORK/proj/dist/$WHL" "$M/tmp/dist/"
chroot_run "$M" "$VENV/bin/pip" install --quiet --no-cache-dir --no-index --no-deps "/tmp/dist/$WHL"
rm -rf "$M/tmp/dist" "$M/root/.cache"
# the non-root user both images run as (the Dockerfiles' `useradd --uid 65532 ... uavtest`)
grep -q '^uavtest:' "$M/etc/passwd" || echo 'uavtest:x:65532:65532::/tmp:/usr/sbin/nologin' >> "$M/etc/passwd"
grep -q '^uavtest:' "$M/etc/group" || echo 'uavtest:x:65532:' >> "$M/etc/group"
chroot_run "$M" /usr/local/bin/uavtest --help >/dev/null 2>&1 || log "note: 'uavtest --help' fails in the image (CLI not written yet?)"
overlay_umount "$M"
python3 "$HERE/mkoci.py" layer "$WORK/proj/upper" "$WORK/proj/layer.tar" >/dev/null
IMAGE_CONFIG=(--env "PATH=$IMAGE_PATH" --env "VIRTUAL_ENV=$VENV" --env LANG=C.UTF-8 --env PYTHONUNBUFFERED=1)
BASE_REF=docker.io/library/uavtest-runner-base:$KB
if [ "$FULL" = 1 ]; then
  python3 "$HERE/mkoci.py" image --out "$OUT" --name "$RUNNER_IMAGE_REF" --cmd '["uavtest", "--help"]' \
    "${IMAGE_CONFIG[@]}" "$A/layer.tar" "$B/layer.tar" "$WORK/proj/layer.tar" >/dev/null
  rm -f "$OUT.base"
else
  if [ ! -f "$B/base-image.tar" ]; then   # layers 1+2 as an image of their own, made once per layer-2 key
    python3 "$HERE/mkoci.py" image --out "$B/base-image.tar.tmp" --name "$BASE_REF" --cmd '["python3"]' \
      "${IMAGE_CONFIG[@]}" "$A/layer.tar" "$B/layer.tar" >/dev/null
    mv "$B/base-image.tar.tmp" "$B/base-image.tar"
  fi
  python3 "$HERE/mkoci.py" image --thin 2 --out "$OUT" --name "$RUNNER_IMAGE_REF" --cmd '["uavtest", "--help"]' \
    "${IMAGE_CONFIG[@]}" "$A/layer.tar" "$B/layer.tar" "$WORK/proj/layer.tar" >/dev/null
  echo "$BASE_REF $B/base-image.tar" > "$OUT.base"
fi
log "image layer 3 (project wheel) + archive: built in $(since "$t0")s -> $OUT ($(du -h "$OUT" | cut -f1))"

# ---------------------------------------------------------------- the operator image: the same layers
# The root Dockerfile's image: entrypoint `uavtest`, command `operator --metrics-port=8080 --liveness-port=8081`,
# uid 65532, HOME and MPLCONFIGDIR in /tmp (the chart mounts an emptyDir there: read-only root filesystem).
t0=$(now)
OP_OUT=$(dirname "$OUT")/uavtest-operator-dev.tar
OP_CONFIG=("${IMAGE_CONFIG[@]}" --env PYTHONDONTWRITEBYTECODE=1 --env HOME=/tmp --env MPLCONFIGDIR=/tmp/matplotlib
  --entrypoint '["uavtest"]' --cmd '["operator", "--metrics-port=8080", "--liveness-port=8081"]'
  --user 65532:65532 --port 8080 --port 8081)
if [ "$FULL" = 1 ]; then
  python3 "$HERE/mkoci.py" image --out "$OP_OUT" --name "$OPERATOR_IMAGE_REF" "${OP_CONFIG[@]}" \
    "$A/layer.tar" "$B/layer.tar" "$WORK/proj/layer.tar" >/dev/null
  rm -f "$OP_OUT.base"
else
  python3 "$HERE/mkoci.py" image --thin 2 --out "$OP_OUT" --name "$OPERATOR_IMAGE_REF" "${OP_CONFIG[@]}" \
    "$A/layer.tar" "$B/layer.tar" "$WORK/proj/layer.tar" >/dev/null
  echo "$BASE_REF $B/base-image.tar" > "$OP_OUT.base"
fi
log "operator image archive: built in $(since "$t0")s -> $OP_OUT"

# ---------------------------------------------------------------- a MinIO image (the chart's throwaway MinIO)
# layer 1 (it has /bin/sh, which the chart's MinIO command uses) + the MinIO server build.sh made; thin, like
# the others, it imports once the runner's base is in containerd (the base holds layer 1)
if [ -x "$BIN/minio" ]; then
  t0=$(now)
  MN=$IMG/minio-$(key "$(cat "$BIN/.stamp-minio" 2>/dev/null)" "$(stat -c %Y "$BIN/minio")")
  if [ ! -f "$MN/layer.tar" ]; then
    rm -rf "$MN"; mkdir -p "$WORK/minio/root/usr/local/bin"
    cp "$BIN/minio" "$WORK/minio/root/usr/local/bin/minio"
    python3 "$HERE/mkoci.py" layer "$WORK/minio/root" "$WORK/minio/layer.tar" >/dev/null
    rm -rf "$WORK/minio/root"; mv "$WORK/minio" "$MN"
  fi
  MN_OUT=$(dirname "$OUT")/minio.tar
  if [ "$FULL" = 1 ]; then thin=(); else thin=(--thin 1); fi
  python3 "$HERE/mkoci.py" image "${thin[@]}" --out "$MN_OUT" --name "$MINIO_IMAGE_REF" --user 65532:65532 \
    --port 9000 --entrypoint '["minio"]' --cmd '["server", "/data"]' "$A/layer.tar" "$MN/layer.tar" >/dev/null
  if [ "$FULL" = 1 ]; then rm -f "$MN_OUT.base"; else echo "$BASE_REF $B/base-image.tar" > "$MN_OUT.base"; fi
  touch "$MN/.used"
  log "minio image archive: built in $(since "$t0")s -> $MN_OUT"
fi

image_cache_hygiene "$A" "$B" "$BE"
