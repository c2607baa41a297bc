"""PNG plots of flights: a top view with the obstacles and x, y, altitude against time.

Figures are built with matplotlib's object API on the Agg canvas (no pyplot global state, no
display), rendered to PNG bytes in memory; ``write_png`` is the one function that touches the
file system. Conventions: the top view has East (y) horizontal and North (x) vertical, as a map;
obstacles are drawn as their rotated footprints; altitude is shown as ``-z``; times are seconds
since takeoff. Replicas are faint, the average bold with its spread band (min–max light,
±1 std darker), the reference dashed.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from uavtest.analysis.average import AverageTrajectory
from uavtest.analysis.geometry import box_corners
from uavtest.analysis.trajectory import Trajectory
from uavtest.errors import BadInput
from uavtest.spec.models import Obstacle

__all__ = ["plot_flight", "plot_run", "write_png"]

REPLICA_COLOR = "tab:blue"
AVERAGE_COLOR = "black"
REFERENCE_COLOR = "tab:red"
OBSTACLE_COLOR = "tab:orange"


def _since_takeoff(tr: Trajectory) -> np.ndarray:
    return tr.t - tr.t[0] if len(tr) else tr.t


def plot_run(
    trajectories: Sequence[Trajectory],
    *,
    average: AverageTrajectory | None = None,
    reference: Trajectory | None = None,
    obstacles: Sequence[Obstacle] = (),
    title: str = "",
    bold_single: bool = False,
) -> bytes:
    """PNG of N replicas (faint), their average (bold, with spread band) and a reference (dashed)."""
    flights = [tr for tr in trajectories if len(tr)]
    fig = Figure(figsize=(13, 7.5), dpi=100)
    FigureCanvasAgg(fig)
    # fixed margins, wide enough for five-digit tick labels: matplotlib's constrained layout
    # measured every label several times, 0.35 s of a 0.8 s plot (half of aggregating one replica)
    grid = fig.add_gridspec(
        3, 2, width_ratios=(1.15, 1), left=0.065, right=0.985, bottom=0.07, top=0.92, wspace=0.17, hspace=0.1
    )
    top = fig.add_subplot(grid[:, 0])
    axes = [fig.add_subplot(grid[i, 1]) for i in range(3)]
    for ax in axes[1:]:
        ax.sharex(axes[0])

    faint = {"color": REPLICA_COLOR, "alpha": 0.9 if bold_single else 0.35, "lw": 1.6 if bold_single else 0.9}
    for k, tr in enumerate(flights):
        label = ("flight" if bold_single else f"replicas ({len(flights)})") if k == 0 else None
        top.plot(tr.y, tr.x, label=label, **faint)
        ts = _since_takeoff(tr)
        for ax, values in zip(axes, (tr.x, tr.y, tr.altitude), strict=True):
            ax.plot(ts, values, **faint)
        top.plot(tr.y[:1], tr.x[:1], "o", color=REPLICA_COLOR, ms=4, alpha=faint["alpha"])

    if average is not None:
        m, sd = average.mean, average.std
        top.plot(m[:, 1], m[:, 0], color=AVERAGE_COLOR, lw=2.4, label=f"average of {average.count}")
        sign = (1.0, 1.0, -1.0)  # altitude = -z: the band flips
        for i, ax in enumerate(axes):
            s = sign[i]
            lo, hi = sorted((s * average.min[:, i], s * average.max[:, i]), key=lambda a: float(a.mean()))
            ax.fill_between(average.t, lo, hi, color=AVERAGE_COLOR, alpha=0.08, lw=0)
            ax.fill_between(
                average.t,
                s * m[:, i] - sd[:, i],
                s * m[:, i] + sd[:, i],
                color=AVERAGE_COLOR,
                alpha=0.18,
                lw=0,
            )
            ax.plot(average.t, s * m[:, i], color=AVERAGE_COLOR, lw=2.2)

    if reference is not None and len(reference):
        top.plot(reference.y, reference.x, "--", color=REFERENCE_COLOR, lw=1.8, label="reference")
        rt = _since_takeoff(reference)
        for ax, values in zip(axes, (reference.x, reference.y, reference.altitude), strict=True):
            ax.plot(rt, values, "--", color=REFERENCE_COLOR, lw=1.5)

    for k, obstacle in enumerate(obstacles):
        corners = box_corners(obstacle)
        top.add_patch(
            Polygon(
                corners[:, ::-1],  # (East, North)
                closed=True,
                facecolor=OBSTACLE_COLOR,
                edgecolor="saddlebrown",
                alpha=0.55,
                label="obstacle" if k == 0 else None,
            )
        )
        cx, cy = obstacle.position.x, obstacle.position.y
        top_alt = obstacle.position.z + obstacle.size.h
        top.annotate(f"{top_alt:g} m", (cy, cx), ha="center", va="center", fontsize=8)

    top.plot([0], [0], marker="*", color="green", ms=11, ls="none", label="home")
    top.set_aspect("equal", adjustable="datalim")
    top.set_xlabel("East y (m)")
    top.set_ylabel("North x (m)")
    top.set_title("top view")
    top.grid(True, alpha=0.3)
    top.legend(loc="best", fontsize=8)
    for ax, name in zip(axes, ("North x (m)", "East y (m)", "altitude −z (m)"), strict=True):
        ax.set_ylabel(name)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time since takeoff (s)")
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    if not flights and average is None:
        top.text(0.5, 0.5, "no flight: the vehicle never took off", transform=top.transAxes, ha="center")
    if title:
        fig.suptitle(title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def plot_flight(
    trajectory: Trajectory,
    *,
    reference: Trajectory | None = None,
    obstacles: Sequence[Obstacle] = (),
    title: str = "",
) -> bytes:
    """PNG of one flight (bold), with a reference (dashed) and obstacles."""
    return plot_run([trajectory], reference=reference, obstacles=obstacles, title=title, bold_single=True)


def write_png(path: Path | str, png: bytes) -> Path:
    """Write PNG bytes to ``path`` (the I/O edge); BadInput when the folder does not exist."""
    p = Path(path)
    if not p.parent.is_dir():
        raise BadInput("cannot write the plot: folder does not exist", file=str(p), field="--plot")
    p.write_bytes(png)
    return p
