#!/usr/bin/env python3
"""Write layers and OCI image archives without a Docker engine.

mkoci.py layer [--empty SUBDIR]... DIR OUT.tar
    Tar DIR as one uncompressed image layer; each --empty SUBDIR is kept without its contents.
    DIR may be an overlayfs upper directory: its whiteouts (0/0 character devices) become
    `.wh.NAME` entries and opaque directories get a `.wh..wh..opq` entry, as the OCI image
    spec wants. Prints the layer's sha256.

mkoci.py image --out OUT.tar --name NAME[:TAG] [--entrypoint JSON] [--cmd JSON] [--env K=V]...
               [--workdir DIR] [--user UID:GID] [--port N]...
               [--thin N] LAYER.tar [LAYER.tar ...]
    Assemble an OCI image layout archive (index.json, oci-layout, blobs) from uncompressed
    layer tars, lowest first, importable with `ctr -n k8s.io images import OUT.tar`.
    --thin N leaves the blobs of the N lowest layers out: such an archive imports only into a
    containerd that has them already (e.g. from an image made of those layers).
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import os
import stat
import sys
import tarfile

CHUNK = 1 << 20
OPAQUE_XATTRS = ("trusted.overlay.opaque", "user.overlay.opaque")


def sha256_file(path: str) -> str:
    """The file's sha256, from the `PATH.sha256` side file that write_layer leaves when it is current."""
    side = path + ".sha256"
    with contextlib.suppress(OSError):
        if os.stat(side).st_mtime >= os.stat(path).st_mtime:
            with open(side) as f:
                return f.read().strip()
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while b := f.read(CHUNK):
            h.update(b)
    return h.hexdigest()


def _is_opaque(path: str) -> bool:
    for name in OPAQUE_XATTRS:
        try:
            if os.getxattr(path, name, follow_symlinks=False) == b"y":
                return True
        except OSError:
            continue
    return False


def _tarinfo(tar: tarfile.TarFile, path: str, arcname: str) -> tarfile.TarInfo:
    ti = tar.gettarinfo(path, arcname)
    ti.uname = ti.gname = ""
    return ti


def write_layer(root: str, out: str, empty: frozenset[str] = frozenset()) -> str:
    """Tar ROOT (sorted, numeric owners, hard links kept) into OUT; return its sha256.

    Directories named in EMPTY (relative to ROOT) are written without their contents."""
    with tarfile.open(out, "w", format=tarfile.PAX_FORMAT) as tar:
        for dirpath, dirnames, filenames in os.walk(root):
            dirnames.sort()
            rel = os.path.relpath(dirpath, root)
            if rel in empty:
                tar.addfile(_tarinfo(tar, dirpath, rel))
                dirnames[:] = []
                continue
            if rel != ".":
                tar.addfile(_tarinfo(tar, dirpath, rel))
                if _is_opaque(dirpath):
                    tar.addfile(tarfile.TarInfo(os.path.join(rel, ".wh..wh..opq")))
            # symlinks to directories are listed in dirnames by os.walk: add them as links
            for name in sorted(filenames + [d for d in dirnames if os.path.islink(os.path.join(dirpath, d))]):
                full = os.path.join(dirpath, name)
                arc = os.path.normpath(os.path.join(rel, name))
                st = os.lstat(full)
                if stat.S_ISCHR(st.st_mode) and st.st_rdev == 0:  # overlayfs whiteout
                    ti = tarfile.TarInfo(os.path.join(os.path.dirname(arc), ".wh." + name))
                    tar.addfile(ti)
                    continue
                ti = _tarinfo(tar, full, arc)
                if ti.isreg():
                    with open(full, "rb") as f:
                        tar.addfile(ti, f)
                else:
                    tar.addfile(ti)
    digest = sha256_file(out)
    with open(out + ".sha256", "w") as f:
        f.write(digest + "\n")
    return digest


def _add_bytes(tar: tarfile.TarFile, name: str, data: bytes) -> None:
    ti = tarfile.TarInfo(name)
    ti.size = len(data)
    ti.mode = 0o644
    tar.addfile(ti, io.BytesIO(data))


def write_image(args: argparse.Namespace) -> None:
    layers = [(path, sha256_file(path), os.path.getsize(path)) for path in args.layers]
    config: dict[str, object] = {
        "Env": args.env or ["PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"]
    }
    if args.entrypoint:
        config["Entrypoint"] = json.loads(args.entrypoint)
    if args.cmd:
        config["Cmd"] = json.loads(args.cmd)
    if args.workdir:
        config["WorkingDir"] = args.workdir
    if args.user:
        config["User"] = args.user
    if args.port:
        config["ExposedPorts"] = {f"{p}/tcp": {} for p in args.port}
    cfg = json.dumps(
        {
            "architecture": "amd64",
            "os": "linux",
            "config": config,
            "rootfs": {"type": "layers", "diff_ids": [f"sha256:{d}" for _, d, _ in layers]},
        },
        sort_keys=True,
    ).encode()
    cfg_digest = hashlib.sha256(cfg).hexdigest()
    manifest = json.dumps(
        {
            "schemaVersion": 2,
            "mediaType": "application/vnd.oci.image.manifest.v1+json",
            "config": {
                "mediaType": "application/vnd.oci.image.config.v1+json",
                "digest": f"sha256:{cfg_digest}",
                "size": len(cfg),
            },
            "layers": [
                {"mediaType": "application/vnd.oci.image.layer.v1.tar", "digest": f"sha256:{d}", "size": size}
                for _, d, size in layers
            ],
        },
        sort_keys=True,
    ).encode()
    man_digest = hashlib.sha256(manifest).hexdigest()
    name = args.name if ":" in args.name.rsplit("/", 1)[-1] else f"{args.name}:latest"
    index = json.dumps(
        {
            "schemaVersion": 2,
            "manifests": [
                {
                    "mediaType": "application/vnd.oci.image.manifest.v1+json",
                    "digest": f"sha256:{man_digest}",
                    "size": len(manifest),
                    "platform": {"architecture": "amd64", "os": "linux"},
                    "annotations": {
                        "io.containerd.image.name": name,
                        "org.opencontainers.image.ref.name": name.rsplit(":", 1)[1],
                    },
                }
            ],
        }
    ).encode()
    tmp = args.out + ".tmp"
    with tarfile.open(tmp, "w") as tar:
        _add_bytes(tar, "oci-layout", b'{"imageLayoutVersion":"1.0.0"}')
        _add_bytes(tar, "index.json", index)
        seen = set()
        for path, digest, _ in layers[args.thin :]:
            if digest not in seen:
                seen.add(digest)
                tar.add(path, arcname=f"blobs/sha256/{digest}")
        _add_bytes(tar, f"blobs/sha256/{cfg_digest}", cfg)
        _add_bytes(tar, f"blobs/sha256/{man_digest}", manifest)
    os.replace(tmp, args.out)
    print(f"{args.out} {name} {len(layers)} layers manifest sha256:{man_digest}")


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="what", required=True)
    lp = sub.add_parser("layer")
    lp.add_argument("--empty", action="append", default=[])
    lp.add_argument("dir")
    lp.add_argument("out")
    ip = sub.add_parser("image")
    ip.add_argument("--out", required=True)
    ip.add_argument("--name", required=True)
    ip.add_argument("--entrypoint")
    ip.add_argument("--cmd")
    ip.add_argument("--env", action="append")
    ip.add_argument("--workdir")
    ip.add_argument("--user")
    ip.add_argument("--port", action="append")
    ip.add_argument("--thin", type=int, default=0)
    ip.add_argument("layers", nargs="+")
    args = ap.parse_args(argv)
    if args.what == "layer":
        print(write_layer(args.dir, args.out, frozenset(e.strip("/") for e in args.empty)))
    else:
        write_image(args)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
