"""How PX4-like the built-in simulator flies: the same plans as the PX4 v1.15 SIH flights in
``../shared/data/px4-sih``, flown in-process over N seeds, measured like PX4 against itself.

For each plan: every built-in flight against every PX4 flight ("built-in vs PX4"), next to every
pair of PX4 flights of that plan ("PX4 vs PX4": PX4's own run-to-run range) and every pair of
built-in flights ("built-in vs built-in": the replicas' spread). Each flight is measured from
its lift-off point and resampled onto normalised time (``uavtest.analysis.fidelity``). Avoidance
is off (the PX4 SIH flights had none). Target: every built-in-vs-PX4 mean inside PX4's range.
Each built-in-vs-PX4 mean is printed with its standard error over the seeds, and a verdict within
two of them of PX4's bound is marked "within noise": more seeds could turn it.

Plans: the competition's mission1 and mission2 (``competition/snippets/case_studies``, their
``mission-params.csv``), PX4 logs run1-3 and sf1; its mission3, no shared PX4 log (only with
``--px4-logs mission3=DIR``); and ``square-mission`` rebuilt from the data
README (MIS_TAKEOFF_ALT 5, MPC_XY_CRUISE 8; takeoff to 10 m, 30 m north, 30 m east, land there),
one PX4 log, so no PX4-vs-PX4 range.

    python bench/bench_fidelity.py [--seeds 25] [--plans mission1,mission2,square]
        [--px4-logs mission2=DIR ...] [--test FILE.yaml=DIR ...]

``--px4-logs PLAN=DIR`` adds every ``*.ulg`` under DIR (e.g. the replica folders of ``uavtest run``
with ``simulator: px4`` on the same plan) to that plan's PX4 flights: PX4 SIH seeds its sensor
noise with ``srand(1234)`` on every start, so the shared logs are few noise realizations.

``--test FILE.yaml=DIR`` measures your own plan: the built-in vehicle flies FILE's mission (its
params, home and wind, avoidance off) and is compared with every ``*.ulg`` under DIR, the same
file flown with ``simulator: px4`` (``uavtest run FILE.yaml --out DIR`` with ``UAVTEST_PX4_BIN``).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import math
import os
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from pyulog import ULog
from rich.console import Console
from rich.table import Table

from uavtest.analysis.attitude_response import (
    AFTER_LIFTOFF,
    AttitudeResponse,
    body_z_from_quaternion,
    body_z_from_thrust,
)
from uavtest.analysis.attitude_response import fit as fit_attitude_response
from uavtest.analysis.estimate_phases import (
    CLIMB_AFTER,
    LEG_RESPONSE_AT,
    LEG_RESPONSE_MIN,
    LEG_RESPONSE_SIGN_AT,
    PositionErrors,
    SpeedErrors,
    VelocityAttitude,
    body_errors_by_speed,
    climb_wander,
    heading_turn_response,
    heading_turn_series,
    leg_start_means,
    leg_start_response,
    position_errors_by_phase,
    tilt_push_response,
    tilt_push_series,
)
from uavtest.analysis.fidelity import (
    FIGURES,
    LIFTOFF_RISE,
    NOISE_Z,
    FlightFigures,
    Spread,
    altitude_drift,
    arrival_velocity_errors,
    body_frame_errors,
    boot_time_correlation,
    braking_velocity_errors,
    displacement_errors,
    displacement_grid,
    estimate_errors,
    estimate_lead,
    flight_figures,
    group_standard_error,
    pairs_between,
    pairs_within,
    pooled_autocorrelation,
    share_noise,
    spread,
    takeoff_turned_back,
    velocity_errors,
    vertical_estimate_errors,
    within_noise,
)
from uavtest.analysis.liftoff import Liftoff, Takeoff, liftoff_figures
from uavtest.analysis.ulog import read_ulog, setpoint_changes, topic, trajectory_from_ulog
from uavtest.analysis.waypoint_passes import (
    CornerExit,
    MidLegBrakes,
    WaypointPass,
    corner_exits,
    first_passes,
    midleg_brakes,
)
from uavtest.errors import BadInput
from uavtest.px4.modes import ARMING_STATE_ARMED, NavState
from uavtest.runner.events import MissionItemInt
from uavtest.runner.progress import ProgressWatch
from uavtest.sitl.geo import Projection
from uavtest.sitl.inprocess import Flight, fly_mission
from uavtest.sitl.mav import MavCmd, MavFrame
from uavtest.sitl.mission import NavItem, from_spec
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.loaders import load_test
from uavtest.spec.mission import mission_items
from uavtest.spec.models import Avoidance, Home

LEG_SPEED = 1.5  # m/s: faster than this after the climb, the vehicle has set off on its first leg

REPO = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("UAVTEST_SHARED_DATA", REPO.parent / "shared" / "data"))
PX4_SIH = SHARED / "px4-sih"
CASES = SHARED / "competition" / "snippets" / "case_studies"

Plan = Callable[[int], tuple[SimConfig, list[NavItem]]]


#: where the PX4 SIH vehicle stood (the logs' SIH_LOC_LAT0 / SIH_LOC_LON0 / SIH_LOC_H0): PX4 sets
#: home where it arms and ignores the plan's planned home, which lies 0.44 m south of it
SIH_HOME = Home(lat=47.397742, lon=8.545594, alt=488.0)


def competition(n: int) -> Plan:
    test = load_test(CASES / f"mission{n}.yaml")
    items = from_spec(mission_items(test.spec))
    # the competition files ask for the `ros` simulator (local planner); the PX4 SIH flights had
    # no avoidance, so neither do these
    return lambda seed: (
        dataclasses.replace(SimConfig.from_spec(test.spec, seed), avoidance=Avoidance.NONE, home=SIH_HOME),
        items,
    )


def from_test(path: Path) -> Plan:
    """The mission of a UavTest file as the built-in vehicle flies it, avoidance off (PX4 SIH
    flies without it)."""
    test = load_test(path)
    items = from_spec(mission_items(test.spec))
    return lambda seed: (
        dataclasses.replace(SimConfig.from_spec(test.spec, seed), avoidance=Avoidance.NONE),
        items,
    )


def square(seed: int) -> tuple[SimConfig, list[NavItem]]:
    home = Home()
    proj = Projection(home.lat, home.lon)
    rel = MavFrame.GLOBAL_RELATIVE_ALT_INT

    def at(seq: int, cmd: int, north: float, east: float, alt: float) -> NavItem:
        lat, lon = proj.reproject(north, east)
        return NavItem(seq, cmd, rel, x=round(lat * 1e7), y=round(lon * 1e7), z=alt)

    items = [
        at(0, MavCmd.NAV_TAKEOFF, 0.0, 0.0, 10.0),
        at(1, MavCmd.NAV_WAYPOINT, 30.0, 0.0, 10.0),
        at(2, MavCmd.NAV_WAYPOINT, 30.0, 30.0, 10.0),
        at(3, MavCmd.NAV_LAND, 30.0, 30.0, 0.0),
    ]
    params = {"MIS_TAKEOFF_ALT": 5.0, "MPC_XY_CRUISE": 8.0}
    return SimConfig(home=home, params=params, seed=seed), items


PLANS: dict[str, tuple[Plan | None, list[str]]] = {
    "mission1": (None, [f"competition-mission1-{r}.ulg" for r in ("run1", "run2", "run3", "sf1")]),
    "mission2": (None, [f"competition-mission2-{r}.ulg" for r in ("run1", "run2", "run3", "sf1")]),
    "square": (square, ["square-mission.ulg"]),
    # no shared PX4 log: fly your own (``simulator: px4``) and pass ``--px4-logs mission3=DIR``
    "mission3": (None, []),
}


@dataclasses.dataclass
class Flights:
    figures: list[FlightFigures]
    #: EKF2's horizontal velocity error on each arrival, every flight's together (m/s)
    arrival_errors: list[float]
    #: EKF2's velocity error per axis and flight at 10 Hz (``velocity_errors``)
    error_series: list = dataclasses.field(default_factory=list)
    #: its vertical velocity error per flight at 10 Hz (``displacement_errors`` of z, vz)
    vertical_series: list = dataclasses.field(default_factory=list)
    #: per flight, how the tilt follows the thrust setpoint (``analysis.attitude_response``)
    attitude: list[AttitudeResponse] = dataclasses.field(default_factory=list)
    #: per flight that logs its ground truth: EKF2's position and velocity error std against it
    truth: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    #: per such flight: EKF2's altitude (its slow drift left out) and climb-rate error std, flying
    vertical_truth: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    #: per flight with ground truth: its altitude error's spread, drift kept (``altitude_drift``)
    altitude_drift: list[float] = dataclasses.field(default_factory=list)
    #: per such flight: by how many seconds of velocity the estimate leads the truth
    lead: list[float] = dataclasses.field(default_factory=list)
    #: per such flight: EKF2's velocity error std fore-aft and sideways (body frame)
    body: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    #: per leg of such flights: EKF2's velocity error along / across it, braking into its end
    braking: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    #: per flight and axis: (log time, velocity error) in the air, for ``boot_time_correlation``
    boot_x: list = dataclasses.field(default_factory=list)
    boot_y: list = dataclasses.field(default_factory=list)
    #: every leg's first pass at its waypoint, every flight's together (``first_passes``)
    passes: list[WaypointPass] = dataclasses.field(default_factory=list)
    #: every waypoint left for a new leg, every flight's together (``corner_exits``)
    exits: list[CornerExit] = dataclasses.field(default_factory=list)
    #: per flight: its trajectory's brakes mid-leg (``midleg_brakes``: FlightTaskAuto offtrack)
    brakes: list[MidLegBrakes] = dataclasses.field(default_factory=list)
    #: per flight with a mission_result: whether its takeoff turned back (``takeoff_turned_back``)
    stalls: list[bool] = dataclasses.field(default_factory=list)
    #: per flight with ground truth: EKF2's velocity error at rest and at cruise (body frame)
    speed_errors: list[SpeedErrors] = dataclasses.field(default_factory=list)
    #: per flight with ground truth: EKF2's position error across the track and at rest
    position_errors: list[PositionErrors] = dataclasses.field(default_factory=list)
    #: per flight: the estimate's horizontal wander in the climb (``climb_wander``), m
    wander: list[float] = dataclasses.field(default_factory=list)
    #: per flight with attitude ground truth: EKF2's tilt error, the kick and the setpoint at lift-off
    liftoffs: list[Liftoff] = dataclasses.field(default_factory=list)
    #: per flight with attitude ground truth: (push, velocity error) at low speed
    push: list = dataclasses.field(default_factory=list)
    #: per flight with attitude ground truth: (heading error x speed, sideways velocity error)
    turn: list = dataclasses.field(default_factory=list)
    #: per leg with attitude ground truth: its velocity error across it after its start, signed
    #: by the heading error (``leg_start_response``)
    legs: list = dataclasses.field(default_factory=list)
    #: per flight: whether it finished its mission (``mission_result``); the others are counted
    #: here and measured nowhere else (a stalled or blocked flight has no path to compare)
    completed: list[bool] = dataclasses.field(default_factory=list)

    def joined(self, other: Flights) -> Flights:
        """These flights and ``other``'s, every measurement together."""
        return Flights(
            **{f.name: getattr(self, f.name) + getattr(other, f.name) for f in dataclasses.fields(self)}
        )


def _measure(ulog: ULog, into: Flights) -> None:
    result = topic(ulog, "mission_result")
    into.completed.append(result is None or bool(result["finished"][-1]))
    if not into.completed[-1]:
        return
    traj = trajectory_from_ulog(ulog)
    into.figures.append(flight_figures(traj))
    lp = ulog.get_dataset("vehicle_local_position").data
    t = lp["timestamp"] / 1e6
    air = (t >= traj.t[0]) & (t <= traj.t[-1])
    window = [lp[k][air] if k != "timestamp" else t[air] for k in ("timestamp", "x", "y", "vx", "vy")]
    ex, ey = velocity_errors(*window)
    into.error_series += [e for e in (ex, ey) if len(e)]
    if len(ex):
        g = displacement_grid(window[0])
        into.boot_x.append((g, ex))
        into.boot_y.append((g, ey))
    into.arrival_errors += arrival_velocity_errors(*window)
    changes = setpoint_changes(ulog)
    into.passes += first_passes(t, lp["x"], lp["y"], changes)
    into.exits += corner_exits(t, lp["x"], lp["y"], changes)
    ts = topic(ulog, "trajectory_setpoint")
    if ts is not None:
        cols = [ts[f"{k}[{i}]"] for k in ("position", "velocity") for i in (0, 1)]
        into.brakes.append(midleg_brakes(ts["timestamp"] / 1e6, *cols, changes))
    if any(d.name == "mission_result" for d in ulog.data_list):
        mr = ulog.get_dataset("mission_result").data
        reached = mr["timestamp"][mr["seq_reached"] >= 0] / 1e6
        flying = t >= traj.t[0]  # from lift-off: before it the estimate may still be converging
        if len(reached):
            into.stalls.append(takeoff_turned_back(t[flying], -lp["z"][flying], float(reached[0])))
            # the climb: from lift-off until the takeoff item is reached or the vehicle sets off
            # (PX4's logs may report the takeoff item late, with the first waypoint)
            risen = np.flatnonzero(traj.altitude >= traj.altitude[0] + LIFTOFF_RISE)
            liftoff = float(traj.t[risen[0]]) if len(risen) else float(traj.t[0])
            off = np.flatnonzero((t > liftoff + CLIMB_AFTER) & (np.hypot(lp["vx"], lp["vy"]) > LEG_SPEED))
            until = min(float(reached[0]), float(t[off[0]]) if len(off) else np.inf)
            with contextlib.suppress(BadInput):  # a climb shorter than 6 s (a low takeoff item)
                into.wander.append(climb_wander(t, lp["x"], lp["y"], liftoff, until))
    att = ulog.get_dataset("vehicle_attitude").data
    vertical = displacement_errors(t[air], lp["z"][air], lp["vz"][air])
    if len(vertical):
        into.vertical_series.append(vertical)
    if any(d.name == "vehicle_local_position_groundtruth" for d in ulog.data_list):
        gt = ulog.get_dataset("vehicle_local_position_groundtruth").data
        cols = ("x", "y", "vx", "vy")
        estimate = np.column_stack([lp[k] for k in cols])
        truth = np.column_stack([gt[k] for k in cols])
        flown = (traj.t[0], traj.t[-1])
        into.truth.append(estimate_errors(t, estimate, gt["timestamp"] / 1e6, truth, flown))
        into.altitude_drift.append(altitude_drift(t, lp["z"], gt["timestamp"] / 1e6, gt["z"], flown))
        into.vertical_truth.append(
            vertical_estimate_errors(
                t,
                np.column_stack([lp["z"], lp["vz"]]),
                gt["timestamp"] / 1e6,
                np.column_stack([gt["z"], gt["vz"]]),
                flown,
            )
        )
        # a flight that never moved (a stalled takeoff) has no lead to measure
        with contextlib.suppress(BadInput):
            into.lead.append(estimate_lead(t, estimate, gt["timestamp"] / 1e6, truth, flown))
        velocity = np.column_stack([lp["vx"], lp["vy"], lp["heading"]])
        into.body.append(body_frame_errors(t, velocity, gt["timestamp"] / 1e6, truth[:, 2:], flown))
        into.braking += braking_velocity_errors(t, estimate, gt["timestamp"] / 1e6, truth[:, 2:], changes)
        inside = (traj.t[0] + 5.0, traj.t[-1] - 5.0)
        into.speed_errors.append(
            body_errors_by_speed(t, velocity, gt["timestamp"] / 1e6, truth[:, 2:], inside)
        )
        into.position_errors.append(
            position_errors_by_phase(t, estimate[:, :2], gt["timestamp"] / 1e6, truth, inside)
        )
        if any(d.name == "vehicle_attitude_groundtruth" for d in ulog.data_list):
            ag = ulog.get_dataset("vehicle_attitude_groundtruth").data
            at = ulog.get_dataset("vehicle_attitude").data
            quat = [np.column_stack([d[f"q[{i}]"] for i in range(4)]) for d in (at, ag)]
            # the horizontal velocities and attitudes, estimate and truth, both series read
            series = VelocityAttitude(
                t,
                estimate[:, 2:],
                gt["timestamp"] / 1e6,
                truth[:, 2:],
                at["timestamp"] / 1e6,
                quat[0],
                ag["timestamp"] / 1e6,
                quat[1],
            )
            with contextlib.suppress(BadInput):  # never slow for 2 s in the window
                into.push.append(tilt_push_series(series, (traj.t[0] + 6.0, traj.t[-1] - 3.0)))
            with contextlib.suppress(BadInput):  # never steady above 2 m/s for 2 s
                into.turn.append(heading_turn_series(series, flown))
            into.legs += leg_start_response(series, changes)
            status = topic(ulog, "vehicle_status")
            armed = [] if status is None else np.flatnonzero(status["arming_state"] == ARMING_STATE_ARMED)
            if ts is not None and len(armed):
                takeoff = Takeoff(
                    float(status["timestamp"][armed[0]]) / 1e6,
                    gt["z"],
                    estimate[:, :2],
                    ts["timestamp"] / 1e6,
                    np.column_stack([ts["position[0]"], ts["position[1]"]]),
                )
                with contextlib.suppress(BadInput):  # armed in the air, or never rose
                    into.liftoffs.append(liftoff_figures(series, takeoff))
    sp = ulog.get_dataset("vehicle_local_position_setpoint").data
    thrust = np.column_stack([sp[f"thrust[{i}]"] for i in range(3)])
    q = np.column_stack([att[f"q[{i}]"] for i in range(4)])
    into.attitude.append(
        fit_attitude_response(
            sp["timestamp"] / 1e6,
            body_z_from_thrust(thrust),
            att["timestamp"] / 1e6,
            body_z_from_quaternion(q),
            (traj.t[0] + AFTER_LIFTOFF, traj.t[-1]),
        )
    )


def _leg_means(legs: list) -> str:
    """``leg_start_means`` as signed values, and how many legs."""
    return " / ".join(f"{v:+.2f}" for v in leg_start_means(legs)) + f" ({len(legs)} legs)"


def _passes(passes: list[WaypointPass]) -> str:
    """Closest first pass (mean, min–max), how many missed the acceptance radius, and the
    median / longest time from the pass to acceptance."""
    closest = [p.closest for p in passes]
    waits = [p.accepted_after for p in passes if np.isfinite(p.accepted_after)]
    missed = sum(p.missed for p in passes)
    wait = f"; accepted after {statistics.median(waits):.1f} s (≤ {max(waits):.1f})" if waits else ""
    spread_ = f"{np.mean(closest):.2f} ({min(closest):.2f}–{max(closest):.2f})"
    return f"{spread_}; {missed}/{len(passes)} missed{wait}"


def _brakes(brakes: list[MidLegBrakes]) -> str:
    """How many legs braked mid-leg, and how far before their end (median, range)."""
    legs = sum(b.legs for b in brakes)
    to_go = [d for b in brakes for d in b.to_go]
    if not to_go:
        return f"0 in {legs} legs"
    where = f"{statistics.median(to_go):.0f} m before the end ({min(to_go):.0f}–{max(to_go):.0f})"
    after = [a for b in brakes for a in b.after]
    when = f"; {statistics.median(after):.1f} s into it, {sum(a < 6.0 for a in after)} within 6 s"
    return f"{len(to_go)} in {legs} legs; {where}{when}"


def _finite_mean(flights: list, attr: str) -> float:
    """The mean of ``attr`` over the flights that have samples for it (not NaN)."""
    values = [getattr(f, attr) for f in flights if np.isfinite(getattr(f, attr))]
    return float(np.mean(values)) if values else float("nan")


def _speed_errors(errors: list[SpeedErrors]) -> str:
    """Fore-aft / sideways rms at rest, then at cruise: the mean over flights that have samples."""
    rest = f"{_finite_mean(errors, 'rest_fore'):.2f} / {_finite_mean(errors, 'rest_side'):.2f}"
    return f"{rest} → {_finite_mean(errors, 'cruise_fore'):.2f} / {_finite_mean(errors, 'cruise_side'):.2f}"


def _position_errors(errors: list[PositionErrors]) -> str:
    """Across the track; at rest: the mean over flights that have samples."""
    return f"{_finite_mean(errors, 'across'):.2f}; {_finite_mean(errors, 'rest'):.2f}"


def _liftoffs(liftoffs: list[Liftoff]) -> str:
    """Each lift-off figure's median (10th–90th percentile), and how many flights."""
    cells = []
    for values in zip(*liftoffs, strict=True):
        p10, p50, p90 = np.percentile(values, (10, 50, 90))
        cells.append(f"{p50:.2f} ({p10:.2f}–{p90:.2f})")
    return "; ".join(cells) + f" ({len(liftoffs)} flights)"


def _wander(wander: list[float]) -> str:
    return f"{statistics.median(wander):.2f}; {np.percentile(wander, 90):.2f} ({len(wander)} flights)"


def _exits(exits: list[CornerExit]) -> str:
    """How many went farther off the new leg than the acceptance radius within 2 s, and the
    median / longest time to be 5 m down it."""
    offtrack = sum(e.offtrack for e in exits)
    down = [e.seconds_down for e in exits if np.isfinite(e.seconds_down)]
    timing = f"; 5 m down it after {statistics.median(down):.1f} s (≤ {max(down):.1f})" if down else ""
    return f"{offtrack}/{len(exits)} offtrack{timing}"


def px4_flights(names: list[str], extra: Sequence[Path] = ()) -> Flights:
    out = Flights([], [])
    for path in [PX4_SIH / name for name in names] + list(extra):
        _measure(read_ulog(path), out)
    return out


def _ulogs(option: str, spec: str, folder: str) -> list[Path]:
    logs = sorted(Path(folder).rglob("*.ulg"))
    if not logs:
        raise SystemExit(f"{option} {spec!r}: no *.ulg under {folder}")
    return logs


def _tests(specs: list[str]) -> list[tuple[Path, list[Path]]]:
    """``FILE=DIR`` arguments: a test file and its PX4 flights (every ``*.ulg`` under DIR)."""
    out = []
    for spec in specs:
        path, sep, folder = spec.rpartition("=")
        if not sep or not path:
            raise SystemExit(f"--test {spec!r}: expected FILE.yaml=DIR")
        if not Path(path).is_file():
            raise SystemExit(f"--test {spec!r}: no test file {path}")
        out.append((Path(path), _ulogs("--test", spec, folder)))
    return out


def _extra_logs(specs: list[str]) -> dict[str, list[Path]]:
    """``PLAN=DIR`` arguments: every ``*.ulg`` under each DIR, per plan."""
    out: dict[str, list[Path]] = {}
    for spec in specs:
        name, sep, folder = spec.partition("=")
        if not sep or name not in PLANS:
            raise SystemExit(f"--px4-logs {spec!r}: expected PLAN=DIR with PLAN one of {', '.join(PLANS)}")
        out.setdefault(name, []).extend(_ulogs("--px4-logs", spec, folder))
    return out


def _blocked(config: SimConfig, items: list[NavItem]) -> Callable[[Vehicle, Flight], bool]:
    """The runner's rule (``uavtest.runner.progress``): a mission flight that makes no progress
    toward its next waypoint for a minute is over, as ``uavtest run`` ends a PX4 flight."""
    watch = ProgressWatch(
        [MissionItemInt(i.seq, int(i.frame), int(i.command), x=i.x, y=i.y, z=i.z) for i in items],
        config.home,
    )

    def stop(vehicle: Vehicle, flight: Flight) -> bool:
        for seq, _ in flight.reached:
            watch.on_reached(seq)
        b = vehicle.body
        mission = vehicle.armed and not vehicle.landed and vehicle.nav_state == NavState.AUTO_MISSION
        watch.on_position(b.x, b.y, b.z, vehicle.time_us // 1000, mission)
        return watch.blocked is not None

    return stop


def builtin_flights(plan: Plan, seeds: int) -> tuple[Flights, float]:
    out = Flights([], [])
    start = time.perf_counter()
    for seed in range(seeds):
        config, items = plan(seed)
        sink = MemorySink()
        fly_mission(config, items, sink=sink, stop=_blocked(config, items))
        _measure(ULog(io.BytesIO(sink.logs[0])), out)
    return out, time.perf_counter() - start


def _error_stats(series: list) -> str:
    """Standard deviation and pooled autocorrelation at 1/2/3/5 s of 10 Hz error series."""
    std = float(np.concatenate(series).std())
    acs = "/".join(f"{pooled_autocorrelation(series, 10 * k):.2f}" for k in (1, 2, 3, 5))
    return f"{std:.2f}; {acs}"


def _with_error(s: Spread, error: float) -> str:
    """A built-in-vs-PX4 cell: its mean ± one standard error over the seeds, and its range."""
    return f"{s.mean:.2f} ± {error:.2f} ({s.low:.2f}–{s.high:.2f})"


def _verdict(inside: bool, noisy: bool) -> str:
    """yes / no; "within noise" when the mean is within ``NOISE_Z`` standard errors of the bound."""
    word = "yes" if inside else "[red]no[/red]"
    return f"{word} (within noise)" if noisy else word


def table(name: str, px4_all: Flights, ours_all: Flights) -> tuple[Table, bool]:
    px4, ours = px4_all.figures, ours_all.figures
    t = Table(title=f"{name}: built-in ({len(ours)} seeds) vs PX4 v1.15 SIH ({len(px4)} runs)")
    t.add_column("figure")
    t.add_column("PX4 vs PX4", justify="right")
    t.add_column("built-in vs PX4", justify="right")
    t.add_column("built-in vs built-in", justify="right")
    t.add_column("inside PX4's range", justify="center")
    t.caption = (
        "built-in vs PX4: mean ± one standard error over the seeds (range); within noise: the mean "
        f"lies within {NOISE_Z:g} standard errors of PX4's bound, more seeds could turn the verdict"
    )
    ok = True
    px4_pairs, between, within = pairs_within(px4), pairs_between(ours, px4), pairs_within(ours)
    for attr, label, unit in FIGURES:
        theirs = spread([getattr(p, attr) for p in px4_pairs]) if px4_pairs else None
        values = [getattr(p, attr) for p in between]
        cross, error = spread(values), group_standard_error(values, len(ours))
        own = spread([getattr(p, attr) for p in within]) if within else None
        inside = "—"
        if theirs is not None:
            inside = _verdict(cross.inside(theirs), within_noise(cross.mean, error, -math.inf, theirs.high))
        ok &= theirs is None or cross.inside(theirs)
        t.add_row(f"{label}, {unit}", str(theirs or "—"), _with_error(cross, error), str(own or "—"), inside)
    ft_px4 = spread([f.flight_time for f in px4])
    times = [f.flight_time for f in ours]
    ft_ours, ft_error = spread(times), group_standard_error(times, len(times))  # a seed each
    # two-sided: a mean flight time outside PX4's range is off either way
    ft_inside = ft_px4.low <= ft_ours.mean <= ft_px4.high
    ok &= len(px4) < 2 or ft_inside
    t.add_row(
        "flight time, s (PX4 / built-in)",
        str(ft_px4),
        _with_error(ft_ours, ft_error),
        "",
        "—"
        if len(px4) < 2
        else _verdict(ft_inside, within_noise(ft_ours.mean, ft_error, ft_px4.low, ft_px4.high)),
    )
    t.add_row(
        "flight-time spread: standard deviation (max − min), s",
        f"{ft_px4.std:.1f} ({ft_px4.high - ft_px4.low:.1f})",
        f"{ft_ours.std:.1f} ({ft_ours.high - ft_ours.low:.1f})",
        "",
        "",
    )
    jit_px4 = spread([f.jitter for f in px4])
    jit_ours = spread([f.jitter for f in ours])
    t.add_row("velocity jitter (10 Hz diff vs 1 s mean), m/s", str(jit_px4), str(jit_ours), "", "")
    if px4_all.arrival_errors and ours_all.arrival_errors:
        a_px4, a_ours = px4_all.arrival_errors, ours_all.arrival_errors
        t.add_row(
            "EKF2 velocity error on arrival, m/s",
            f"{statistics.median(a_px4):.2f} ({min(a_px4):.2f}–{max(a_px4):.2f})",
            f"{statistics.median(a_ours):.2f} ({min(a_ours):.2f}–{max(a_ours):.2f})",
            "",
            "",
        )
    if px4_all.passes and ours_all.passes:
        t.add_row(
            "first pass at a waypoint: closest, m; missed the acceptance radius; s to acceptance",
            _passes(px4_all.passes),
            _passes(ours_all.passes),
            "",
            "",
        )
    if px4_all.exits and ours_all.exits:
        t.add_row(
            "leaving a waypoint for a new leg: farther off it than the acceptance radius within "
            "2 s (FlightTaskAuto offtrack); s to be 5 m down it",
            _exits(px4_all.exits),
            _exits(ours_all.exits),
            "",
            "",
        )
    if px4_all.brakes and ours_all.brakes:
        t.add_row(
            "braking mid-leg (FlightTaskAuto offtrack: the trajectory below 2.5 m/s from 5 s into "
            "a leg of 40 m or more until 10 m before its end)",
            _brakes(px4_all.brakes),
            _brakes(ours_all.brakes),
            "",
            "",
        )
    if px4_all.speed_errors and ours_all.speed_errors:
        t.add_row(
            "EKF2 velocity error against the truth, body frame fore-aft / sideways, rms m/s: at rest "
            "(< 0.5 m/s) → at a steady cruise (> 4.2 m/s)",
            _speed_errors(px4_all.speed_errors),
            _speed_errors(ours_all.speed_errors),
            "",
            "",
        )
    if px4_all.position_errors and ours_all.position_errors:
        t.add_row(
            "EKF2 position error against the truth, mean magnitude, m: across the track on a leg "
            "(> 3.5 m/s); at rest in the air (< 0.5 m/s)",
            _position_errors(px4_all.position_errors),
            _position_errors(ours_all.position_errors),
            "",
            "",
        )
    if px4_all.wander and ours_all.wander:
        t.add_row(
            "the estimate's horizontal wander in the climb (from 5 s after lift-off to the takeoff "
            "item), median; p90, m",
            _wander(px4_all.wander),
            _wander(ours_all.wander),
            "",
            "",
        )
    if px4_all.liftoffs and ours_all.liftoffs:
        t.add_row(
            "lift-off: EKF2's tilt error before the release, °; the true tilt's peak after it, °; "
            "the estimate off the takeoff setpoint 0.3 m up, m: median (p10–p90)",
            _liftoffs(px4_all.liftoffs),
            _liftoffs(ours_all.liftoffs),
            "",
            "",
        )
    regressions = (
        (
            "velocity error against g x the tilt error, leaky over 1 s, below 1 m/s: slope "
            "(correlation); 1: EKF2 misses the push",
            tilt_push_response,
            px4_all.push,
            ours_all.push,
        ),
        (
            "sideways velocity error against EKF2's heading error x speed, steady above 2 m/s: "
            "slope (correlation); PX4's heading and velocity errors go together",
            heading_turn_response,
            px4_all.turn,
            ours_all.turn,
        ),
    )
    for label, response, theirs_series, ours_series in regressions:
        if theirs_series and ours_series:
            theirs, mine = response(theirs_series), response(ours_series)
            t.add_row(
                label,
                f"{theirs.slope:.2f} ({theirs.correlation:.2f})",
                f"{mine.slope:.2f} ({mine.correlation:.2f})",
                "",
                "",
            )
    if px4_all.legs and ours_all.legs:
        at = " / ".join(f"{s:g}" for s in LEG_RESPONSE_AT)
        t.add_row(
            f"EKF2 velocity error across a new leg (≥ {LEG_RESPONSE_MIN:g} m), signed by its heading error "
            f"{LEG_RESPONSE_SIGN_AT:g} s in, mean m/s at {at} s after the leg's start; PX4: the "
            "miss turns into a bias that pulls the estimate back",
            _leg_means(px4_all.legs),
            _leg_means(ours_all.legs),
            "",
            "",
        )
    if not all(px4_all.completed) or not all(ours_all.completed):
        t.add_row(
            "flights that finished the mission (the others, stalled or blocked, measured nowhere "
            "else in this table)",
            f"{sum(px4_all.completed)} of {len(px4_all.completed)}",
            f"{sum(ours_all.completed)} of {len(ours_all.completed)}",
            "",
            "",
        )
    if px4_all.stalls and ours_all.stalls:
        t.add_row(
            "takeoffs that turned back (FlightTaskAuto back to the track's start on the ground)",
            f"{sum(px4_all.stalls)} of {len(px4_all.stalls)}",
            f"{sum(ours_all.stalls)} of {len(ours_all.stalls)}",
            "",
            "",
        )
    if px4_all.error_series and ours_all.error_series:
        t.add_row(
            "EKF2 velocity error std, m/s; autocorr. 1/2/3/5 s",
            _error_stats(px4_all.error_series),
            _error_stats(ours_all.error_series),
            "",
            "",
        )
    if px4_all.vertical_series and ours_all.vertical_series:
        t.add_row(
            "EKF2 vertical velocity error std, m/s; autocorr. 1/2/3/5 s",
            _error_stats(px4_all.vertical_series),
            _error_stats(ours_all.vertical_series),
            "",
            "",
        )
    if px4_all.truth and ours_all.truth:
        t.add_row(
            "EKF2 error against the ground truth: position / velocity std, m, m/s",
            _pair_means(px4_all.truth),
            _pair_means(ours_all.truth),
            "",
            "",
        )
        t.add_row(
            "EKF2 vertical error against the ground truth while flying: altitude (its 10 s drift "
            "left out) / climb-rate std, m, m/s",
            _pair_means(px4_all.vertical_truth),
            _pair_means(ours_all.vertical_truth),
            "",
            "",
        )
        t.add_row(
            "EKF2 altitude error against the ground truth while flying, its drift kept: spread "
            "within a flight (std), m: mean (min–max)",
            _spread(px4_all.altitude_drift),
            _spread(ours_all.altitude_drift),
            "",
            "",
        )
        t.add_row(
            "EKF2 position's lead on the ground truth, s of velocity: mean (min–max)",
            _spread(px4_all.lead),
            _spread(ours_all.lead),
            "",
            "",
        )
        t.add_row(
            "EKF2 velocity error against the ground truth braking into a waypoint (0-3 s after "
            "acceptance): along / across the leg, mean, m/s",
            _pair_means(px4_all.braking, "legs"),
            _pair_means(ours_all.braking, "legs"),
            "",
            "",
        )
    if px4_all.body and ours_all.body:
        t.add_row(
            "EKF2 velocity error against the ground truth, body frame: fore-aft / sideways std, m/s",
            _pair_means(px4_all.body),
            _pair_means(ours_all.body),
            "",
            "",
        )
    if len(px4_all.boot_x) > 1 and len(ours_all.boot_x) > 1:
        t.add_row(
            "EKF2 velocity error alike between flights at equal time since start: median best "
            "correlation within ±2 s, x / y",
            _boot(px4_all),
            _boot(ours_all),
            "",
            "",
        )
    if px4_all.attitude and ours_all.attitude:
        t.add_row(
            "attitude response (tilt after thrust setpoint): delay + lag, median",
            _response(px4_all.attitude),
            _response(ours_all.attitude),
            "",
            "",
        )
    return t, ok


def yardstick_table(name: str, shared: Flights, yours: Flights, ours: Flights) -> Table:
    """The target's yardstick held to PX4 itself: the ``--px4-logs`` flights against the shared
    logs alone, beside the built-in flights against them, each mean with the shared logs' own range.

    The shared logs of a plan are few noise realizations (SIH's ``srand(1234)``), so their range
    is narrow; this says whether other flights of PX4 v1.15 SIH fall inside it.
    """
    t = Table(
        title=f"{name}: against the {len(shared.figures)} shared PX4 logs alone, "
        f"your {len(yours.figures)} PX4 flights and the built-in ones"
    )
    t.add_column("figure")
    t.add_column("shared PX4 vs shared PX4", justify="right")
    t.add_column("your PX4 vs shared PX4", justify="right")
    t.add_column("built-in vs shared PX4", justify="right")
    ranges = pairs_within(shared.figures)
    pairs = (pairs_between(yours.figures, shared.figures), pairs_between(ours.figures, shared.figures))
    for attr, label, unit in FIGURES:
        theirs = spread([getattr(p, attr) for p in ranges]) if ranges else None
        cells = []
        for between in pairs:
            mean = spread([getattr(p, attr) for p in between])
            mark = "" if theirs is None else (" (inside)" if mean.inside(theirs) else " [red](outside)[/red]")
            cells.append(f"{mean.mean:.2f}{mark}")
        t.add_row(f"{label}, {unit}", str(theirs or "—"), *cells)
    return t


def _spread(values: list[float]) -> str:
    return f"{np.mean(values):.3f} ({min(values):.3f}–{max(values):.3f}, {len(values)} flights)"


def _pair_means(pairs: list[tuple[float, float]], what: str = "flights") -> str:
    """Per-flight pairs (position / velocity, fore-aft / sideways): each one's mean over flights."""
    a = statistics.mean(p[0] for p in pairs)
    b = statistics.mean(p[1] for p in pairs)
    return f"{a:.2f} / {b:.2f} ({len(pairs)} {what})"


def _boot(flights: Flights) -> str:
    return f"{boot_time_correlation(flights.boot_x):.2f} / {boot_time_correlation(flights.boot_y):.2f}"


def _response(fits: list[AttitudeResponse]) -> str:
    delay = statistics.median(f.delay for f in fits)
    tau = statistics.median(f.tau for f in fits)
    return f"{delay:.2f} + {tau:.2f} s"


def compare(console: Console, name: str, plan: Plan, shared: Flights, yours: Flights, seeds: int) -> bool:
    """Fly ``plan`` over ``seeds`` seeds, print it against the PX4 flights, say whether every
    mean is inside PX4's range (trivially so with fewer than two PX4 flights: no range)."""
    px4 = shared.joined(yours)
    ours, wall = builtin_flights(plan, seeds)
    if not px4.figures or not ours.figures:
        console.print(f"[red]{name}: no flight that finished its mission to compare[/red]")
        return False
    t, ok = table(name, px4, ours)
    console.print(t)
    if not ok and len(px4.boot_x) > 1 and share_noise(px4.boot_x, px4.boot_y):
        console.print(
            f"  [yellow]note: these {len(px4.figures)} PX4 flights share their noise (EKF2 velocity errors "
            f"alike at equal time since start: {_boot(px4)}): PX4 SIH seeds it with srand(1234) at "
            "every start, so their run-to-run range is that of few noise realizations, while the "
            "built-in vehicle draws independent noise per seed. More PX4 flights (--px4-logs) give "
            "a yardstick across realizations.[/yellow]"
        )
    if yours.figures and len(shared.figures) >= 2:
        console.print(yardstick_table(name, shared, yours, ours))
    per = statistics.mean(f.flight_time for f in ours.figures)
    console.print(f"  {seeds} built-in flights in {wall:.1f} s wall ({per:.0f} s flight each)\n")
    return ok or len(px4.figures) < 2


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seeds", type=int, default=25)
    parser.add_argument(
        "--plans", default=None, help="default mission1,mission2,square (none with --test alone)"
    )
    parser.add_argument(
        "--px4-logs",
        action="append",
        default=[],
        metavar="PLAN=DIR",
        help="more PX4 flights of PLAN: every *.ulg under DIR (repeatable)",
    )
    parser.add_argument(
        "--test",
        action="append",
        default=[],
        metavar="FILE=DIR",
        help="your own plan: a UavTest file and its PX4 flights, every *.ulg under DIR (repeatable)",
    )
    args = parser.parse_args()
    extra = _extra_logs(args.px4_logs)
    tests = _tests(args.test)
    plans = args.plans if args.plans is not None else ("" if tests else "mission1,mission2,square")
    names = [n for n in plans.split(",") if n]
    if names and not PX4_SIH.is_dir():
        raise SystemExit(f"{PX4_SIH} not found (set UAVTEST_SHARED_DATA to the real data folder)")
    console = Console(width=150)
    all_ok = True
    for name in names:
        if name not in PLANS:
            raise SystemExit(f"unknown plan {name!r}: allowed {', '.join(PLANS)}")
        plan, logs = PLANS[name]
        if plan is None:
            plan = competition(int(name[-1]))
        shared = px4_flights(logs)
        yours = px4_flights([], extra.get(name, []))
        if not shared.figures and not yours.figures:
            raise SystemExit(f"{name}: no PX4 flight of this plan in the shared data: --px4-logs {name}=DIR")
        if name in extra:
            console.print(f"{name}: {len(logs)} shared PX4 logs and {len(extra[name])} from --px4-logs")
        all_ok &= compare(console, name, plan, shared, yours, args.seeds)
    for path, logs in tests:
        console.print(f"{path.name}: {len(logs)} PX4 logs")
        yours = px4_flights([], logs)
        all_ok &= compare(console, path.stem, from_test(path), Flights([], []), yours, args.seeds)
    console.print(
        "every built-in-vs-PX4 mean inside PX4's run-to-run range" if all_ok else "[red]not all inside[/red]"
    )
    sys.exit(0 if all_ok else 1)


if __name__ == "__main__":
    main()
