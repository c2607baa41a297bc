"""Test harness: real processes the suite starts by itself (a one-node Kubernetes cluster, MinIO).

- `harness.cluster`: build the binaries (tests/cluster/build.sh), start/stop a cluster on 127.0.0.1 with a
  real kubelet + containerd or a kwok fake node, build and import the runner image.
- `harness.minio`: a MinIO server on a free loopback port with random credentials.
- `harness.net`: `free_udp_port`.
- `harness.sitl`: `running_sitl` (a `uavtest sitl` process for a `with` block), `stop_process`,
  `free_running_argv` (the command line MAVSDK tests use), `eventually`.
- `harness.mavlink_client`: `connect` (a pymavlink udpin connection as a ground station) and the
  shared lockstep `LockstepClient`.

Everything lives under the cache dir (`$UAVTEST_CACHE`, default ~/.cache/uavtest) and a temporary
state dir per cluster or server; nothing is left running or mounted once stopped.
"""

from .cluster import Cluster, ClusterError, build_binaries, build_runner_image, start_cluster
from .minio import MinioServer, start_minio

__all__ = [
    "Cluster",
    "ClusterError",
    "MinioServer",
    "build_binaries",
    "build_runner_image",
    "start_cluster",
    "start_minio",
]
