"""Start and stop the e2e Kubernetes cluster (scripts in tests/cluster/) from Python.

    build_binaries()                      # tests/cluster/build.sh: cached, ~10-20 min from nothing
    c = start_cluster(real_node=True)     # etcd + apiserver + kcm + scheduler + containerd + kubelet
    c.kubectl("get", "nodes")             # always against this cluster's own kubeconfig
    c.import_image(build_runner_image())  # the runner image, from the current working tree
    c.import_image(image_archives()[OPERATOR_IMAGE])  # the operator image that build wrote beside it
    c.helm("install", "uavtest", "charts/uavtest", "-n", "ns", "--create-namespace")
    c.stop()                              # down-real.sh: nothing left on the host

Only one real-node cluster can run on a host at a time; kwok clusters (control plane + fake node, pods
never run) can run beside it. Every port is on 127.0.0.1 and picked free at start (a real-node cluster's
apiserver listens on all addresses and CoreDNS on the pod bridge's: pods reach them there).
"""

from __future__ import annotations

import atexit
import contextlib
import json
import logging
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "CACHE_DIR",
    "CLUSTER_SCRIPTS",
    "MINIO_IMAGE",
    "OPERATOR_IMAGE",
    "REPO_ROOT",
    "RUNNER_IMAGE",
    "Cluster",
    "ClusterError",
    "KubectlError",
    "build_binaries",
    "build_runner_image",
    "containerd_ref",
    "free_ports",
    "image_archives",
    "start_cluster",
    "terminate_on_sigterm",
]

log = logging.getLogger("uavtest.harness")

REPO_ROOT = Path(__file__).resolve().parents[2]
CLUSTER_SCRIPTS = REPO_ROOT / "tests" / "cluster"
CACHE_DIR = Path(os.environ.get("UAVTEST_CACHE") or Path.home() / ".cache" / "uavtest")
BIN_DIR = CACHE_DIR / "bin"
RUNNER_IMAGE = "uavtest-runner:dev"
"""The name pod specs use for the runner image (with imagePullPolicy: Never)."""
RUNNER_IMAGE_ARCHIVE = CACHE_DIR / "share" / "uavtest-runner-dev.tar"
OPERATOR_IMAGE = "uavtest-operator:dev"
"""The operator image: the root Dockerfile's, built without Docker beside the runner's."""
MINIO_IMAGE = "uavtest.local/minio:dev"
"""MinIO (the binary build.sh makes, on the Debian base) for the chart's throwaway MinIO."""

BUILD_TIMEOUT = 60 * 60
UP_TIMEOUT = 5 * 60
REAL_NODE_TIMEOUT = 20 * 60  # up-real.sh may wait for another session's real node (UAVTEST_REAL_NODE_WAIT)
DOWN_TIMEOUT = 3 * 60
PORT_NAMES = (
    "ETCD_PORT",
    "ETCD_PEER_PORT",
    "APISERVER_PORT",
    "KCM_PORT",
    "SCHEDULER_PORT",
    "KUBELET_PORT",
    "KUBELET_HEALTHZ_PORT",
    "KWOK_PORT",
    "KUBE_PROXY_PORT",
    "KUBE_PROXY_METRICS_PORT",
    "DNS_READY_PORT",
)
# flags that would point kubectl at another cluster than the harness's own
FOREIGN_FLAGS = ("--kubeconfig", "--context", "--cluster", "--server", "-s", "--user", "--token")


class ClusterError(RuntimeError):
    """The harness could not build, start or talk to its cluster."""


class KubectlError(ClusterError):
    """kubectl exited non-zero."""

    def __init__(self, args: Sequence[str], returncode: int, stderr: str) -> None:
        super().__init__(f"kubectl {' '.join(args)} -> exit {returncode}: {stderr.strip()}")
        self.returncode = returncode
        self.stderr = stderr


def _run_script(script: str, *args: str, env: Mapping[str, str] | None = None, timeout: float) -> str:
    """Run tests/cluster/SCRIPT; return its combined output, raise ClusterError with it on failure."""
    cmd = ["bash", str(CLUSTER_SCRIPTS / script), *args]
    # its own process group: if we are interrupted (Ctrl-C, SIGTERM, timeout) the script and everything it
    # started so far (go builds, half a control plane) are ended together, not left behind
    proc = subprocess.Popen(
        cmd,
        env={**os.environ, **(env or {})},
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        out, _ = proc.communicate(timeout=timeout)
    except BaseException as e:
        _kill_group(proc)
        if isinstance(e, subprocess.TimeoutExpired):
            raise ClusterError(f"{script} timed out after {timeout}s") from e
        raise
    if proc.returncode != 0:
        raise ClusterError(f"{script} {' '.join(args)} failed (exit {proc.returncode}):\n{out}")
    for line in out.splitlines():  # the scripts' own progress and timing lines
        if line.startswith("[uavtest-cluster]"):
            log.info("%s", line)
    return out


def _kill_group(proc: subprocess.Popen[str]) -> None:
    """TERM the process group of PROC, give the script up to 5 s, then KILL whatever is left of it."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGTERM)
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(5)
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(5)


def build_binaries(*steps: str) -> str:
    """Build (once; cached) the cluster binaries: tests/cluster/build.sh [STEP...]. Returns its log."""
    return _run_script("build.sh", *steps, timeout=BUILD_TIMEOUT)


def build_runner_image(
    repo_root: Path | str = REPO_ROOT, out: Path | str | None = None, *, full: bool = False
) -> Path:
    """Build the runner image archive from REPO_ROOT's working tree; return the OCI archive's path.

    The Debian base and the dependency venv layers are cached; the project layer is rebuilt every call.
    By default the archive is thin (project layer only; `Cluster.import_image` brings the cached base
    along); full=True writes a self-contained one for any `ctr images import`.
    """
    archive = Path(out) if out else RUNNER_IMAGE_ARCHIVE
    args = [str(repo_root), str(archive), *(["--full"] if full else [])]
    _run_script("build-runner-image.sh", *args, timeout=BUILD_TIMEOUT)
    return archive


HELM_HOMES = ("CACHE", "CONFIG", "DATA")  # helm's dirs: in the cluster dir, not in $HOME


def image_archives(runner_archive: Path | str = RUNNER_IMAGE_ARCHIVE) -> dict[str, Path]:
    """The archives build_runner_image writes: image name -> OCI archive (MinIO if build.sh made it)."""
    d = Path(runner_archive).parent
    out = {RUNNER_IMAGE: Path(runner_archive), OPERATOR_IMAGE: d / "uavtest-operator-dev.tar"}
    if (d / "minio.tar").exists():
        out[MINIO_IMAGE] = d / "minio.tar"
    return out


def containerd_ref(name: str) -> str:
    """NAME as containerd's CRI stores it: `uavtest-runner:dev` -> `docker.io/library/uavtest-runner:dev`."""
    first, _, rest = name.partition("/")
    if not rest:
        return f"docker.io/library/{name}"
    if "." in first or ":" in first or first == "localhost":
        return name
    return f"docker.io/{name}"


def free_ports(n: int) -> list[int]:
    """N distinct free TCP ports on 127.0.0.1 (held open together while choosing, so they differ)."""
    socks = []
    try:
        for _ in range(n):
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.bind(("127.0.0.1", 0))
            socks.append(s)
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


@dataclass(eq=False)
class Cluster:
    """A running cluster started by `start_cluster`; `kubectl` only ever talks to this one."""

    dir: Path
    real_node: bool
    kwok: bool
    ports: dict[str, int]
    stopped: bool = field(default=False, init=False)

    @property
    def kubeconfig(self) -> Path:
        return self.dir / "kubeconfig"

    @property
    def server(self) -> str:
        return f"https://127.0.0.1:{self.ports['APISERVER_PORT']}"

    @property
    def node_name(self) -> str:
        """The node pods land on: "localhost" (real kubelet) or "kwok-node-0" (fake)."""
        return "localhost" if self.real_node else "kwok-node-0"

    @property
    def logs_dir(self) -> Path:
        return self.dir / "logs"

    def env(self) -> dict[str, str]:
        """os.environ with KUBECONFIG pointing at this cluster (for subprocesses: kopf, uavtest, ...)."""
        return {**os.environ, "KUBECONFIG": str(self.kubeconfig)}

    # ------------------------------------------------------------------ kubectl
    def kubectl(self, *args: str, input: str | None = None, check: bool = True, timeout: float = 120) -> str:
        """Run kubectl against this cluster; return stdout. Raises KubectlError on a non-zero exit."""
        for a in args:
            if a.split("=", 1)[0] in FOREIGN_FLAGS:
                raise ClusterError(f"kubectl {a!r}: the harness only talks to its own cluster")
        if self.stopped:
            raise ClusterError("cluster is stopped")
        proc = subprocess.run(
            [str(BIN_DIR / "kubectl"), f"--kubeconfig={self.kubeconfig}", *args],
            input=input,
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
            env={k: v for k, v in os.environ.items() if k != "KUBECONFIG"},
        )
        if check and proc.returncode != 0:
            raise KubectlError(args, proc.returncode, proc.stderr)
        return proc.stdout

    def kubectl_json(self, *args: str, timeout: float = 120) -> Any:
        return json.loads(self.kubectl(*args, "-o", "json", timeout=timeout))

    def apply(self, *objects: Mapping[str, Any], namespace: str | None = None) -> str:
        """kubectl apply the given manifests (dicts)."""
        doc = json.dumps({"apiVersion": "v1", "kind": "List", "items": list(objects)})
        ns = ["-n", namespace] if namespace else []
        return self.kubectl("apply", *ns, "-f", "-", input=doc)

    def create_namespace(self, name: str) -> str:
        self.apply({"apiVersion": "v1", "kind": "Namespace", "metadata": {"name": name}})

        # pods are refused until the namespace's default service account exists
        def has_sa() -> bool:
            return self.kubectl("get", "sa", "default", "-n", name, check=False) != ""

        if not self.wait_until(has_sa, 60):
            raise ClusterError(f"namespace {name}: no default service account after 60 s")
        return name

    def delete_namespace(self, name: str, wait: bool = False) -> None:
        self.kubectl(
            "delete", "namespace", name, "--ignore-not-found", f"--wait={str(wait).lower()}", timeout=180
        )

    def pod_phase(self, namespace: str, name: str) -> str:
        return self.kubectl("get", "pod", name, "-n", namespace, "-o", "jsonpath={.status.phase}")

    def wait_pod_done(self, namespace: str, name: str, timeout: float = 180) -> str:
        """Wait until the pod is Succeeded or Failed; return the phase."""
        phase = ""

        def done() -> bool:
            nonlocal phase
            phase = self.pod_phase(namespace, name)
            return phase in ("Succeeded", "Failed")

        if not self.wait_until(done, timeout):
            desc = self.kubectl("describe", "pod", name, "-n", namespace, check=False)
            raise ClusterError(f"pod {namespace}/{name} still {phase!r} after {timeout}s:\n{desc}")
        return phase

    @staticmethod
    def wait_until(pred: Callable[[], object], timeout: float, interval: float = 0.25) -> bool:
        """Poll PRED until true or TIMEOUT seconds have passed; return whether it became true."""
        end = time.monotonic() + timeout
        while True:
            if pred():
                return True
            if time.monotonic() > end:
                return False
            time.sleep(interval)

    # ------------------------------------------------------------------ images (real node)
    def ctr(self, *args: str, timeout: float = 600) -> str:
        """Run containerd's ctr in the k8s.io namespace of this cluster's containerd."""
        if not self.real_node:
            raise ClusterError("no containerd: this cluster has no real node")
        proc = subprocess.run(
            [
                str(CACHE_DIR / "deb" / "x" / "usr" / "bin" / "ctr"),
                "--address",
                str(self.dir / "ctr" / "containerd.sock"),
                "-n",
                "k8s.io",
                *args,
            ],
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
        if proc.returncode != 0:
            raise ClusterError(f"ctr {' '.join(args)} -> exit {proc.returncode}: {proc.stderr.strip()}")
        return proc.stdout

    def import_image(self, archive: Path | str) -> None:
        """Import an OCI archive into the node's containerd (tests/cluster/import-image.sh).

        A thin archive from build_runner_image brings its base image along (imported only when missing)."""
        if not self.real_node:
            raise ClusterError("no containerd: this cluster has no real node")
        _run_script("import-image.sh", str(self.dir), str(archive), timeout=UP_TIMEOUT)

    def tag_image(self, source: str, target: str) -> None:
        """Give an imported image a second name (`ctr images tag`), e.g. the one a chart defaults to."""
        self.ctr("images", "tag", "--force", containerd_ref(source), containerd_ref(target))

    def helm(self, *args: str, timeout: float = 300) -> str:
        """Run the cached helm against this cluster (its kubeconfig only); return stdout."""
        for a in args:
            if a.split("=", 1)[0] in (*FOREIGN_FLAGS, "--kube-context", "--kube-apiserver", "--kube-token"):
                raise ClusterError(f"helm {a!r}: the harness only talks to its own cluster")
        proc = subprocess.run(
            [str(BIN_DIR / "helm"), f"--kubeconfig={self.kubeconfig}", *args],
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
            cwd=REPO_ROOT,
            env={**os.environ, **{f"HELM_{k}_HOME": str(self.dir / "helm" / k) for k in HELM_HOMES}},
        )
        if proc.returncode != 0:
            raise ClusterError(f"helm {' '.join(args)} -> exit {proc.returncode}: {proc.stderr.strip()}")
        return proc.stdout

    # ------------------------------------------------------------------ lifecycle
    def assert_own(self) -> None:
        """Refuse to go on unless the kubeconfig in use is this cluster's own, on 127.0.0.1."""
        cfg = json.loads(self.kubectl("config", "view", "--minify", "-o", "json"))
        servers = [c["cluster"]["server"] for c in cfg.get("clusters", [])]
        if servers != [self.server]:
            raise ClusterError(f"kubeconfig {self.kubeconfig} points at {servers}, not {self.server}")

    def log_tail(self, lines: int = 30) -> str:
        out = []
        for f in sorted(self.logs_dir.glob("*.log")):
            text = f.read_text(errors="replace").splitlines()[-lines:]
            out.append(f"--- {f.name}\n" + "\n".join(text))
        return "\n".join(out)

    def stop(self, keep_dir: bool | None = None) -> None:
        """Stop everything this cluster started and undo its host changes; remove its dir."""
        if self.stopped:
            return
        self.stopped = True
        _LIVE.discard(self)
        if keep_dir is None:
            keep_dir = os.environ.get("UAVTEST_KEEP_CLUSTER_DIR") == "1"
        script = "down-real.sh" if self.real_node else "down.sh"
        try:
            with _sigterm_ignored():  # a SIGTERM now must not cut the clean-up short
                _run_script(script, str(self.dir), timeout=DOWN_TIMEOUT)
        finally:
            if not keep_dir:
                shutil.rmtree(self.dir, ignore_errors=True)


_LIVE: set[Cluster] = set()
_LIVE_LOCK = threading.Lock()


@atexit.register
def _stop_all() -> None:
    """Last resort: a cluster whose owner never called stop() (crash, interrupted session)."""
    with _LIVE_LOCK:
        live = list(_LIVE)
    for c in live:
        with contextlib.suppress(Exception):
            c.stop()


def start_cluster(
    *, real_node: bool = True, kwok: bool = False, parent_dir: Path | str | None = None, build: bool = True
) -> Cluster:
    """Start a cluster in a new temporary dir: control plane, plus a real node and/or a kwok node.

    With build=True first runs build.sh (a no-op when the cache is warm). A real node needs root.
    On failure everything already started is stopped again and ClusterError says why.
    """
    if real_node and os.geteuid() != 0:
        raise ClusterError("a real node (kubelet + containerd) needs root")
    if build:
        build_binaries()
    d = Path(tempfile.mkdtemp(prefix="uavtest-k8s-", dir=parent_dir))
    ports = dict(zip(PORT_NAMES, free_ports(len(PORT_NAMES)), strict=True))
    cluster = Cluster(dir=d, real_node=real_node, kwok=kwok, ports=ports)
    with _LIVE_LOCK:
        _LIVE.add(cluster)
    env = {k: str(v) for k, v in ports.items()}
    try:
        opts = [*(["--kwok"] if kwok else []), *(["--pods"] if real_node else [])]
        _run_script("up.sh", str(d), *opts, env=env, timeout=UP_TIMEOUT)
        if real_node:
            _run_script("up-real.sh", str(d), env=env, timeout=REAL_NODE_TIMEOUT)
        cluster.assert_own()
    except BaseException:
        with contextlib.suppress(Exception):
            cluster.stop(keep_dir=os.environ.get("UAVTEST_KEEP_CLUSTER_DIR") == "1")
        raise
    return cluster


@contextlib.contextmanager
def _sigterm_ignored() -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def terminate_on_sigterm() -> Iterator[None]:
    """Turn SIGTERM into KeyboardInterrupt while inside, so pytest still runs fixture teardowns (and so
    stops clusters and servers) when CI or a timeout terminates the session."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: object) -> None:
        raise KeyboardInterrupt(f"signal {signum}")

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
