"""A self-contained UavTest manifest, ready for ``kubectl apply``.

Everything a test refers to is inlined: the QGC plan (``mission.plan``), the params
(``vehicle.params``), the commands, and the similarity reference flight as
``assertions.similarity.reference.points`` (t, x, y, z rows read from the ULog with
``uavtest.analysis.ulog``, evenly thinned to at most ``MAX_REFERENCE_POINTS``). Defaults are
written out too, so the manifest means the same with a later uavtest.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from uavtest.errors import BadInput, InfrastructureError
from uavtest.spec.loaders import resolve_references
from uavtest.spec.models import UavTest

__all__ = ["MAX_REFERENCE_POINTS", "reference_points", "render"]

MAX_REFERENCE_POINTS = 500
_DECIMALS = 3  # millimetres and milliseconds: far below any flight's noise


def reference_points(
    log_file: Path, *, field: str = "spec.assertions.similarity.logFile"
) -> list[list[float]]:
    """Rows ``[t, x, y, z]`` of the flight in a PX4 ULog (takeoff to landing), at most 500 of them."""
    try:
        from uavtest.analysis.ulog import read_ulog, trajectory_from_ulog
    except ImportError as e:  # pragma: no cover - the analysis package ships with uavtest
        raise InfrastructureError(f"cannot read reference logs: {e}") from e
    trajectory = trajectory_from_ulog(read_ulog(log_file), source=str(log_file))
    n = len(trajectory.t)
    if n < 2:
        raise BadInput(
            "the reference log holds no flight (the vehicle never took off)",
            file=str(log_file),
            field=field,
            allowed="a PX4 ULog of a flight",
        )
    index = np.unique(np.linspace(0, n - 1, min(n, MAX_REFERENCE_POINTS)).round().astype(int))
    columns = np.column_stack([trajectory.t, trajectory.x, trajectory.y, trajectory.z])[index]
    return [[round(float(v), _DECIMALS) + 0.0 for v in row] for row in columns]  # + 0.0: no -0.0


def render(test: UavTest, *, name: str | None = None, namespace: str | None = None) -> dict[str, Any]:
    """The manifest of ``test`` as a plain dict, with every referenced file inlined.

    Files a test still refers to (a UavTest built in Python rather than by ``load_test``) are
    resolved from the current folder.
    """
    spec = test.spec
    if (
        spec.vehicle.params_file is not None
        or spec.commands_file is not None
        or (spec.mission is not None and spec.mission.plan_file is not None)
    ):
        test = resolve_references(test, None)
    doc = test.model_dump(by_alias=True, exclude_none=True, mode="json")
    similarity = test.spec.assertions.similarity
    if similarity is not None and similarity.log_file is not None:
        sim = doc["spec"]["assertions"]["similarity"]
        sim["reference"] = {"points": reference_points(Path(similarity.log_file))}
        del sim["logFile"]
    metadata = {k: v for k, v in doc["metadata"].items() if v not in ({}, None)}
    if name is not None:
        metadata["name"] = name
    if namespace is not None:
        metadata["namespace"] = namespace
    manifest = {
        "apiVersion": doc["apiVersion"],
        "kind": doc["kind"],
        "metadata": metadata,
        "spec": doc["spec"],
    }
    # the manifest must stand on its own: validate it with the same model
    UavTest.model_validate(manifest)
    return manifest
