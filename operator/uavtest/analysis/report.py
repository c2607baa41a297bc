"""``uavtest report LOG.ulg``: one flight log's metrics and verdict, as a table or JSON.

``build_report`` is pure (a parsed ULog and an optional test in, a ``LogReport`` out);
``report_command`` is the CLI edge: it reads the files, prints, writes the plot and returns the
exit code (0 pass, 1 fail). Without a test, the default assertions apply with no obstacles; a
mission in the log (``mission_result``) must then have been completed.
"""

from __future__ import annotations

from pathlib import Path

import yaml
from pydantic import Field, ValidationError
from pyulog import ULog
from rich.console import Console
from rich.table import Table

from uavtest.analysis.models import ReplicaResult, Verdict
from uavtest.analysis.similarity import dtw, frechet
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.ulog import (
    crash_reported,
    flight_window,
    log_trajectory,
    mission_progress_from_ulog,
    read_ulog,
)
from uavtest.analysis.verdict import judge, judge_flight
from uavtest.errors import BadInput, ExitCode, MissingFile
from uavtest.spec.models import Assertions, UavTest

__all__ = ["LogReport", "build_report", "load_test_file", "report_command"]


class LogReport(ReplicaResult):
    """A ``ReplicaResult`` for one log, plus what the log itself says."""

    log: str
    test: str | None = None
    took_off: bool
    takeoff_time: float | None = Field(None, description="s on the vehicle clock")
    landing_time: float | None = Field(None, description="s on the vehicle clock; end of log if not landed")
    landed: bool
    flight_source: str = Field(
        description="what the flight was cut by: vehicle_land_detected, arming, motion"
    )
    samples: int = Field(description="vehicle_local_position samples in the flight")
    log_samples: int = Field(description="vehicle_local_position samples in the whole log")
    log_duration: float = Field(description="s from the first to the last position sample")
    topics: int = Field(description="distinct topics logged")
    dtw_per_step: float | None = Field(None, description="DTW to the reference, mean metres per step")
    dtw_raw: float | None = Field(None, description="DTW to the reference as dtaidistance gives it")
    frechet: float | None = Field(None, description="discrete Fréchet distance to the reference, metres")


def build_report(
    ulog: ULog,
    *,
    log_name: str,
    test: UavTest | None = None,
    test_name: str | None = None,
    reference: Trajectory | None = None,
) -> tuple[LogReport, Trajectory]:
    """Judge one parsed log (pure): the report and the flight's trajectory."""
    window = flight_window(ulog, source=log_name)
    full = log_trajectory(ulog, window, source=log_name)
    flight = full.between(window.start, window.end) if window.took_off else full.between(float("inf"), 0)
    mission = mission_progress_from_ulog(ulog)
    if test is not None:
        metrics, assertions, verdict, reason = judge(
            flight, test.spec, mission=mission, reference=reference, crash=crash_reported(ulog)
        )
    else:
        metrics, assertions, verdict, reason = judge_flight(
            flight, Assertions(), mission=mission, reference=reference
        )
    extra: dict[str, float | None] = {}
    if reference is not None and len(reference) and len(flight):
        d = dtw(flight, reference)
        extra = {"dtw_per_step": d.per_step, "dtw_raw": d.raw, "frechet": frechet(flight, reference)}
    if not window.took_off:
        note = "no flight: the vehicle never took off"
        reason = f"{note}; {reason}" if reason else note
    report = LogReport(
        index=0,
        seed=0,
        verdict=verdict,
        reason=reason,
        assertions=assertions,
        metrics=metrics,
        sim_time=metrics.flight_time,
        wall_time=None,
        log=log_name,
        test=test_name,
        took_off=window.took_off,
        takeoff_time=window.start,
        landing_time=window.end,
        landed=window.landed,
        flight_source=window.source,
        samples=len(flight),
        log_samples=len(full),
        log_duration=full.duration,
        topics=len({d.name for d in ulog.data_list}),
        **extra,
    )
    return report, flight


# --------------------------------------------------------------------------- edges


def load_test_file(path: Path) -> UavTest:
    """The test in ``path``: spec loaders (native / Aerialist YAML) when present, else native YAML."""
    try:
        from uavtest.spec.loaders import load_test
    except ImportError:
        load_test = None
    if load_test is not None:
        return load_test(path)
    if not path.is_file():
        raise MissingFile(str(path))
    try:
        return UavTest.model_validate(yaml.safe_load(path.read_text()))
    except (yaml.YAMLError, ValidationError) as e:
        raise BadInput(f"not a UavTest: {e}", file=str(path)) from e


def _reference_log(test: UavTest, test_path: Path) -> Path | None:
    """The similarity assertion's reference log, relative to the test file or a parent folder."""
    sim = test.spec.assertions.similarity
    if sim is None or sim.log_file is None:
        return None
    candidate = Path(sim.log_file)
    if candidate.is_absolute():
        return candidate
    for folder in [test_path.resolve().parent, *test_path.resolve().parent.parents]:
        if (folder / candidate).is_file():
            return folder / candidate
    raise MissingFile(
        sim.log_file, referenced_from=str(test_path), field="spec.assertions.similarity.logFile"
    )


def _cut(path: Path) -> Trajectory:
    ulog = read_ulog(path)
    window = flight_window(ulog, source=str(path))
    full = log_trajectory(ulog, window, source=str(path))
    return full.between(window.start, window.end) if window.took_off else full


def _num(v: float | None, unit: str = "", digits: int = 2) -> str:
    return "—" if v is None else f"{v:.{digits}f}{(' ' + unit) if unit else ''}"


def render_table(report: LogReport, console: Console) -> None:
    """Print the report as rich tables."""
    m = report.metrics
    assert m is not None
    table = Table(title=f"uavtest report · {report.log}", title_justify="left", show_header=False)
    table.add_column("metric", style="bold")
    table.add_column("value")
    if report.took_off:
        flight = f"{_num(m.flight_time, 's', 1)}  ({report.takeoff_time:.1f} s → {report.landing_time:.1f} s"
        flight += f"{'' if report.landed else ', log ended in the air'}; by {report.flight_source})"
    else:
        flight = f"no flight: never took off (by {report.flight_source})"
    table.add_row("flight time", flight)
    table.add_row("max altitude", _num(m.max_altitude, "m"))
    table.add_row(
        "min obstacle distance (3-D)",
        _num(m.min_obstacle_distance, "m")
        + ("" if m.min_obstacle_distance is not None else " (no obstacles)"),
    )
    if m.min_obstacle_distance_2d is not None:
        table.add_row("2-D distance (competition)", _num(m.min_obstacle_distance_2d, "m"))
    if m.competition_points is not None:
        table.add_row("competition points", f"{m.competition_points} (5: < 0.25 m, 2: < 1 m, 1: < 1.5 m)")
    table.add_row("collision", "yes" if m.collision else "no")
    if m.waypoints_total is not None:
        done = "completed" if m.mission_completed else "not completed"
        table.add_row("mission", f"{done} ({m.waypoints_reached}/{m.waypoints_total} items)")
    else:
        table.add_row("mission", "— (no mission in the log)")
    if report.dtw_per_step is not None:
        table.add_row("DTW to reference", f"{report.dtw_per_step:.2f} m per step (raw {report.dtw_raw:.1f})")
        table.add_row("Fréchet to reference", _num(report.frechet, "m"))
    if m.geofence_violation is not None:
        table.add_row("geofence violation", _num(m.geofence_violation, "m"))
    table.add_row(
        "samples", f"{report.samples} in flight / {report.log_samples} in log ({report.log_duration:.1f} s)"
    )
    table.add_row("topics", str(report.topics))
    console.print(table)
    if report.assertions:
        checks = Table(title="assertions", title_justify="left")
        for col in ("assertion", "result", "value", "limit", "message"):
            checks.add_column(col)
        for a in report.assertions:
            checks.add_row(
                a.name,
                "[green]pass[/]" if a.passed else "[red]fail[/]",
                _num(a.value),
                _num(a.limit),
                a.message,
            )
        console.print(checks)
    colour = "green" if report.verdict == Verdict.PASS else "red"
    line = f"verdict: [bold {colour}]{report.verdict.value}[/]"
    if report.reason:
        line += f" — {report.reason}"
    console.print(line, highlight=False)


def report_command(
    log: Path,
    test: Path | None = None,
    reference: Path | None = None,
    plot: Path | None = None,
    json_out: bool = False,
) -> int:
    """``uavtest report``: print the metrics and verdict of ``log``; 0 pass, 1 fail."""
    from uavtest.analysis.plots import plot_flight, write_png

    ulog = read_ulog(log)
    uav_test = load_test_file(test) if test is not None else None
    ref_path = reference
    if ref_path is None and uav_test is not None and test is not None:
        ref_path = _reference_log(uav_test, test)
    ref = _cut(ref_path) if ref_path is not None else None
    report, flight = build_report(
        ulog,
        log_name=str(log),
        test=uav_test,
        test_name=str(test) if test is not None else None,
        reference=ref,
    )
    if plot is not None:
        obstacles = uav_test.spec.world.obstacles if uav_test is not None else []
        png = plot_flight(
            flight, reference=ref, obstacles=obstacles, title=f"{log.name} · {report.verdict.value}"
        )
        write_png(plot, png)
    if json_out:
        print(report.model_dump_json(indent=2))
    else:
        console = Console()
        render_table(report, console)
        if plot is not None:
            console.print(f"plot: {plot}")
    return int(ExitCode.PASS if report.verdict == Verdict.PASS else ExitCode.FAIL)
