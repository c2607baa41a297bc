#!/bin/bash
# import-image.sh DIR ARCHIVE.tar : import an image archive into the containerd of the real node of cluster DIR
# (up-real.sh). For a thin archive from build-runner-image.sh (ARCHIVE.tar.base exists) the base image is
# imported first, only if containerd lacks it; older bases and image IDs no named image uses any more are
# removed, so the persistent containerd root does not grow build after build.
set -euo pipefail
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
D=$(cd "${1:?usage: import-image.sh DIR ARCHIVE.tar}" && pwd); AR=${2:?usage: import-image.sh DIR ARCHIVE.tar}
CTR=("$DEBX/usr/bin/ctr" --address "$D/ctr/containerd.sock" -n k8s.io)
t0=$(now)
if [ -f "$AR.base" ]; then
  read -r BASE_REF BASE_AR < "$AR.base"
  refs=$("${CTR[@]}" images ls -q)
  if ! grep -qxF "$BASE_REF" <<< "$refs"; then
    for r in $(grep "^${BASE_REF%:*}:" <<< "$refs" || true); do "${CTR[@]}" images rm "$r" >/dev/null; done
    "${CTR[@]}" images import "$BASE_AR" >/dev/null
    log "imported base image $BASE_REF in $(since "$t0")s"
  fi
fi
"${CTR[@]}" images import "$AR" >/dev/null
# CRI keeps a "sha256:<config digest>" ref for every image it saw: drop those whose manifest no named image uses
"${CTR[@]}" images ls | awk 'NR > 1 { print $1, $3 }' > "$D/images.txt"
awk '$1 !~ /^sha256:/ { print $2 }' "$D/images.txt" | sort -u > "$D/images.keep"
awk '$1 ~ /^sha256:/' "$D/images.txt" | while read -r ref digest; do
  grep -qxF "$digest" "$D/images.keep" || "${CTR[@]}" images rm "$ref" >/dev/null 2>&1 || true
done
rm -f "$D/images.txt" "$D/images.keep"
log "imported $AR in $(since "$t0")s"
