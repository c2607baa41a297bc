"""How alike two flights of the same plan are, in path and in time: the figures of the fidelity bench.

Each flight is measured from its lift-off point (``from_liftoff``): PX4's local origin is the
EKF origin and SIH logs sit about a metre off the ground at rest, so positions are taken
relative to where the vehicle was when it lifted off (the ground below it for the altitude), and
time from the moment it lifted off. Both flights are then resampled onto normalised time
(``NORMALISED_POINTS`` points from lift-off to landing), which compares *where along the path,
when*, whatever the flights' durations:

- ``dtw``: DTW per point (metres) between the resampled paths: the path's shape;
- ``mean_distance``: mean distance at equal normalised time (metres): the shape and the timing;
- ``speed_error``: mean absolute difference of ground speed at equal normalised time (m/s);
- ``altitude_error``: mean absolute difference of altitude at equal normalised time (metres);
- ``flight_time``: lift-off to landing (seconds), per flight;
- ``jitter``: per flight, the RMS of the horizontal velocity from 10 Hz position differences
  around its 1 s moving average (m/s): white noise on a logged position shows here (PX4's EKF2
  output is smooth: a few cm/s).

And from the logged velocity next to the logged position (``arrival_velocity_errors``):

- velocity error on arrival: after each leg (faster than ``ARRIVAL_FAST`` m/s, then slower than
  ``ARRIVAL_SLOW``), the median over ``ARRIVAL_WINDOW`` seconds of |logged velocity − the logged
  position's own displacement over 1 s| (m/s). PX4 SIH's EKF2 position follows its ground truth
  (its 1 s displacement within 0.05 m/s median of the truth's, ``square-mission.ulg``) but its
  velocity estimate does not (0.19-0.21 m/s standard deviation): the velocity loop flies the
  estimate, so this error is how far off a waypoint the vehicle holds (error / ``MPC_XY_P``) and
  whether it makes the acceptance radius at once or creeps onto it.

And against a logged ground truth (PX4 SIH's ``vehicle_local_position_groundtruth``):
``estimate_errors``, ``estimate_lead``, ``body_frame_errors``, and ``braking_velocity_errors``,
the velocity error along and across a leg as the vehicle brakes into its waypoint (EKF2 misses
part of the braking, and its heading error turns the rest sideways).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np

from uavtest.analysis.similarity import dtw_points
from uavtest.analysis.trajectory import Trajectory
from uavtest.analysis.waypoint_passes import LEG_MIN
from uavtest.errors import BadInput

__all__ = [
    "ARRIVAL_FAST",
    "ARRIVAL_SLOW",
    "ARRIVAL_WINDOW",
    "FIGURES",
    "LIFTOFF_RISE",
    "NOISE_Z",
    "NORMALISED_POINTS",
    "FlightFigures",
    "PairFigures",
    "Spread",
    "altitude_drift",
    "arrival_velocity_errors",
    "body_frame_errors",
    "body_frame_series",
    "boot_time_correlation",
    "braking_velocity_errors",
    "compare",
    "displacement_errors",
    "displacement_grid",
    "errors_on",
    "estimate_errors",
    "flight_figures",
    "from_liftoff",
    "group_standard_error",
    "normalised",
    "pairs_between",
    "pairs_within",
    "pooled_autocorrelation",
    "share_noise",
    "spread",
    "takeoff_turned_back",
    "velocity_errors",
    "vertical_estimate_errors",
    "within_noise",
]

NORMALISED_POINTS = 200
LIFTOFF_RISE = 0.3  # m above the altitude at the start of the flight window: lifted off
JITTER_RATE = 10.0  # Hz
JITTER_WINDOW = 1.0  # s
ARRIVAL_FAST = 3.0  # m/s: a leg
ARRIVAL_SLOW = 1.0  # m/s: arrived
ARRIVAL_WINDOW = 3.0  # s
ARRIVAL_RATE = 20.0  # Hz

#: the pair figures, in table order: attribute, label, unit
FIGURES: tuple[tuple[str, str, str], ...] = (
    ("dtw", "DTW per point (path shape)", "m"),
    ("mean_distance", "mean distance at equal normalised time", "m"),
    ("speed_error", "speed-profile error (mean |Δ speed|)", "m/s"),
    ("altitude_error", "altitude error (mean |Δ altitude|)", "m"),
)


def from_liftoff(traj: Trajectory, *, rise: float = LIFTOFF_RISE) -> Trajectory:
    """The flight from the moment it lifted off, relative to the lift-off point.

    ``traj`` is a flight window (takeoff to landing, e.g. ``trajectory_from_ulog``). Lift-off is
    the first sample ``rise`` metres above the window's first altitude; x, y are taken relative
    to the position there, z relative to the window's first sample (the ground), t from there.
    """
    if len(traj) < 2:
        raise BadInput("a flight needs at least two samples to be measured", value=len(traj))
    alt = traj.altitude
    above = np.flatnonzero(alt >= alt[0] + rise)
    if not len(above):
        raise BadInput(f"the flight never climbed {rise} m: no lift-off", value=float(alt.max() - alt[0]))
    i = int(above[0])
    return Trajectory(
        traj.t[i:] - traj.t[i],
        traj.x[i:] - traj.x[i],
        traj.y[i:] - traj.y[i],
        traj.z[i:] - traj.z[0],
        traj.heading[i:],
    )


def normalised(traj: Trajectory, points: int = NORMALISED_POINTS) -> np.ndarray:
    """(points, 3) positions at equally spaced fractions of the flight's duration."""
    if len(traj) < 2 or traj.duration <= 0:
        raise BadInput("a flight needs a duration to be resampled onto normalised time")
    grid = np.linspace(traj.t[0], traj.t[-1], points)
    return np.column_stack([np.interp(grid, traj.t, a) for a in (traj.x, traj.y, traj.z)])


@dataclass(frozen=True, slots=True)
class FlightFigures:
    """One flight measured from lift-off: its duration and how much its logged velocity jitters."""

    flight_time: float
    jitter: float
    path: np.ndarray  # (NORMALISED_POINTS, 3)
    speed: np.ndarray  # (NORMALISED_POINTS,) ground speed, m/s


def _jitter(traj: Trajectory) -> float:
    if traj.duration < 2 * JITTER_WINDOW:
        return 0.0
    r = traj.resample(JITTER_RATE)
    v = np.hypot(np.diff(r.x), np.diff(r.y)) * JITTER_RATE
    n = int(JITTER_WINDOW * JITTER_RATE)
    smooth = np.convolve(v, np.ones(n) / n, mode="same")
    core = slice(n, len(v) - n)
    return float(np.sqrt(np.mean((v[core] - smooth[core]) ** 2))) if len(v) > 2 * n else 0.0


def flight_figures(flight: Trajectory, points: int = NORMALISED_POINTS) -> FlightFigures:
    """Measure one flight window (``trajectory_from_ulog``) from its lift-off."""
    f = from_liftoff(flight)
    path = normalised(f, points)
    dt = f.duration / (points - 1)
    speed = np.hypot(np.gradient(path[:, 0], dt), np.gradient(path[:, 1], dt))
    return FlightFigures(flight_time=f.duration, jitter=_jitter(f), path=path, speed=speed)


def displacement_errors(t: np.ndarray, p: np.ndarray, v: np.ndarray, rate: float = 10.0) -> np.ndarray:
    """One axis: the logged velocity minus the logged position's own displacement over 1 s,
    sampled at ``rate`` Hz over the window (empty when it is shorter than 2 s)."""
    if len(t) < 2 or t[-1] - t[0] < 2.0:
        return np.empty(0)
    g = displacement_grid(t, rate)
    return np.interp(g, t, v) - (np.interp(g + 0.5, t, p) - np.interp(g - 0.5, t, p))


def displacement_grid(t: np.ndarray, rate: float = 10.0) -> np.ndarray:
    """The times ``displacement_errors`` samples at: half a second in from either end."""
    return np.arange(t[0] + 0.5, t[-1] - 0.5, 1.0 / rate)


def velocity_errors(
    t: np.ndarray, x: np.ndarray, y: np.ndarray, vx: np.ndarray, vy: np.ndarray, rate: float = 10.0
) -> tuple[np.ndarray, np.ndarray]:
    """Per horizontal axis, ``displacement_errors``."""
    return displacement_errors(t, x, vx, rate), displacement_errors(t, y, vy, rate)


def estimate_errors(
    t: np.ndarray,
    estimate: np.ndarray,
    t_truth: np.ndarray,
    truth: np.ndarray,
    window: tuple[float, float],
    rate: float = 10.0,
) -> tuple[float, float]:
    """How far the estimate is from the ground truth a simulator logs next to it (PX4 SITL's
    ``vehicle_local_position_groundtruth``): the standard deviation per horizontal axis of the
    position error (about its mean: the EKF origin is not the simulator's) and of the velocity
    error, averaged over x and y. ``estimate`` and ``truth``: (N, 4) columns x, y, vx, vy."""
    g = _grid(window, rate, "estimate errors")
    std = errors_on(g, t, estimate, t_truth, truth, 4).std(axis=0)
    return float((std[0] + std[1]) / 2), float((std[2] + std[3]) / 2)


VERTICAL_TREND_S = 10.0  # s: the altitude error's slower drift, left out of vertical_estimate_errors
VERTICAL_AIRBORNE = 1.0  # m: truly this far above the window's lowest point, the vehicle is flying


def vertical_estimate_errors(
    t: np.ndarray,
    estimate: np.ndarray,
    t_truth: np.ndarray,
    truth: np.ndarray,
    window: tuple[float, float],
    rate: float = 10.0,
) -> tuple[float, float]:
    """How far the estimated altitude and climb rate are from the ground truth while flying: the
    standard deviation of the altitude error about its ``VERTICAL_TREND_S`` moving mean (EKF2's
    GNSS/baro-referenced altitude drifts slowly; this is its faster wander) and of the climb-rate
    error, over the samples where the truth is ``VERTICAL_AIRBORNE`` above its lowest point in the
    window, the ground (touchdown and EKF2's shift on the ground left out).
    ``estimate``, ``truth``: (N, 2) columns z, vz."""
    g = _grid(window, rate, "vertical estimate errors")
    e = errors_on(g, t, estimate, t_truth, truth, 2)
    n = max(1, int(VERTICAL_TREND_S * rate))
    if len(g) <= n:
        raise BadInput("vertical estimate errors: the window is shorter than the trend", value=len(g) / rate)
    flying = _flying(g, t_truth, truth[:, 0], "vertical estimate errors")
    # the moving mean of the flying samples alone: the shift on the ground does not leak into it
    box = np.ones(n)
    weight = np.maximum(np.convolve(flying, box, mode="same"), 1)
    trend = np.convolve(e[:, 0] * flying, box, mode="same") / weight
    return float((e[flying, 0] - trend[flying]).std()), float(e[flying, 1].std())


def altitude_drift(
    t: np.ndarray,
    z: np.ndarray,
    t_truth: np.ndarray,
    z_truth: np.ndarray,
    window: tuple[float, float],
    rate: float = 10.0,
) -> float:
    """The spread of the estimated altitude's error against the ground truth within one flight,
    its slow drift kept (what ``vertical_estimate_errors`` leaves out): the standard deviation of
    estimate minus truth (z, NED) about its mean over the samples where the truth is
    ``VERTICAL_AIRBORNE`` above its lowest point in the window. The controller flies the estimate,
    so this is how far the vehicle truly strays above and below the altitude it holds."""
    g = _grid(window, rate, "altitude drift")
    e = errors_on(g, t, z[:, None], t_truth, z_truth[:, None], 1)[:, 0]
    return float(e[_flying(g, t_truth, z_truth, "altitude drift")].std())


def _flying(g: np.ndarray, t_truth: np.ndarray, z_truth: np.ndarray, what: str) -> np.ndarray:
    """Where on ``g`` the truth (z, NED) is ``VERTICAL_AIRBORNE`` above its lowest point there;
    ``what`` names the figure a window without a flight fails."""
    altitude = -np.interp(g, t_truth, z_truth)
    flying = altitude - altitude.min() > VERTICAL_AIRBORNE
    if flying.sum() < 2:
        raise BadInput(f"{what}: the truth never flew in the window")
    return flying


def _grid(window: tuple[float, float], rate: float, what: str) -> np.ndarray:
    """Times across ``window`` at ``rate`` Hz; ``what`` names the figure a too short window fails."""
    g = np.arange(window[0], window[1], 1.0 / rate)
    if len(g) < 2:
        raise BadInput(f"{what}: the window is empty")
    return g


def errors_on(
    g: np.ndarray, t: np.ndarray, estimate: np.ndarray, t_truth: np.ndarray, truth: np.ndarray, n: int
) -> np.ndarray:
    """The estimate's first ``n`` columns minus the truth's, both interpolated onto ``g``."""
    return np.column_stack(
        [np.interp(g, t, estimate[:, i]) - np.interp(g, t_truth, truth[:, i]) for i in range(n)]
    )


def estimate_lead(
    t: np.ndarray,
    estimate: np.ndarray,
    t_truth: np.ndarray,
    truth: np.ndarray,
    window: tuple[float, float],
    span: float = 1.0,
    rate: float = 10.0,
) -> float:
    """By how many seconds of its velocity the estimated position leads the ground truth (PX4
    SIH: EKF2 fuses SIH's undelayed GPS as EKF2_GPS_DELAY old). Fitted on changes over ``span``
    seconds, where the true velocity changed by more than 0.5 m/s, so a slowly drifting offset
    does not count: change of the position error = lead x change of the true velocity, both
    horizontal axes pooled. ``estimate``: (N, 2 or more) columns x, y first; ``truth``: (M, 4) x,
    y, vx, vy."""
    g = np.arange(window[0], window[1], 1.0 / rate)
    k = round(span * rate)
    if len(g) <= k:
        raise BadInput("estimate lead: the window is shorter than the span")
    err = errors_on(g, t, estimate, t_truth, truth, 2)
    vel = np.column_stack([np.interp(g, t_truth, truth[:, 2 + i]) for i in range(2)])
    d_e, d_v = (err[k:] - err[:-k]).ravel(), (vel[k:] - vel[:-k]).ravel()
    moved = np.abs(d_v) > 0.5
    if not moved.any():
        raise BadInput("estimate lead: the true velocity never changed by 0.5 m/s within the span")
    return float(np.sum(d_e[moved] * d_v[moved]) / np.sum(d_v[moved] ** 2))


def body_frame_errors(
    t: np.ndarray,
    estimate: np.ndarray,
    t_truth: np.ndarray,
    truth: np.ndarray,
    window: tuple[float, float],
    rate: float = 10.0,
) -> tuple[float, float]:
    """The estimated horizontal velocity's error against the ground truth, turned into the body
    frame by the estimated heading: its standard deviation fore-aft (body x) and sideways (body
    y), each about its mean. ``estimate``: (N, 3) vx, vy (NED), heading (rad), as
    ``vehicle_local_position`` logs them; ``truth``: (M, 2) vx, vy. PX4 SIH's accelerometer noise
    is 0.5 / 1.7 m/s^2 on the body's x / y axis (``sih.cpp``), and EKF2's velocity error follows it."""
    fore, side = body_frame_series(_grid(window, rate, "body-frame errors"), t, estimate, t_truth, truth)
    return float(fore.std()), float(side.std())


def body_frame_series(
    g: np.ndarray, t: np.ndarray, estimate: np.ndarray, t_truth: np.ndarray, truth: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The estimated horizontal velocity's error against the truth on the times ``g``, fore-aft
    and sideways in the body frame of the estimated heading (``body_frame_errors``' inputs)."""
    e = errors_on(g, t, estimate, t_truth, truth, 2)
    psi = np.interp(g, t, np.unwrap(estimate[:, 2]))
    c, s = np.cos(psi), np.sin(psi)
    return c * e[:, 0] + s * e[:, 1], -s * e[:, 0] + c * e[:, 1]


def boot_time_correlation(series: Sequence[tuple[np.ndarray, np.ndarray]], lag: float = 2.0) -> float:
    """How alike flights' error series are at equal time since their simulator started: the
    median over pairs of the best Pearson correlation within +- ``lag`` seconds, on the time both
    cover. ``series``: per flight (t, e) at one common rate. Flights with independent noise give
    about 0.2 (the best of several lags of noise); PX4 SIH seeds its noise with ``srand(1234)`` at
    every start, so its flights share one realization, shifted by scheduling."""
    if len(series) < 2:
        raise BadInput("boot-time correlation needs at least two flights", value=len(series))
    best: list[float] = []
    for (ta, ea), (tb, eb) in combinations(series, 2):
        dt = float(np.median(np.diff(ta)))
        lo, hi = max(ta[0], tb[0]), min(ta[-1], tb[-1])
        g = np.arange(lo, hi, dt)
        n = round(lag / dt)
        if len(g) <= 2 * n + 10:
            continue
        a, b = np.interp(g, ta, ea), np.interp(g, tb, eb)
        cs = [np.corrcoef(a[n + k : len(g) - n + k], b[n : len(g) - n])[0, 1] for k in range(-n, n + 1)]
        best.append(float(np.nanmax(cs)))
    if not best:
        raise BadInput("boot-time correlation: no two flights overlap in time")
    return float(np.median(best))


#: boot-time correlation from which flights share their noise: independent noise gives about 0.2
#: (the best of several lags), PX4 SIH's runs of a plan 0.45-0.93 (the shared logs)
SHARED_NOISE = 0.4


def share_noise(
    x: Sequence[tuple[np.ndarray, np.ndarray]], y: Sequence[tuple[np.ndarray, np.ndarray]]
) -> bool:
    """Whether flights share one noise realization (PX4 SIH's ``srand(1234)``): the mean of the
    x and y velocity errors' ``boot_time_correlation`` reaches ``SHARED_NOISE``. Their
    run-to-run range is then that of few realizations, narrower than across realizations."""
    return (boot_time_correlation(x) + boot_time_correlation(y)) / 2 >= SHARED_NOISE


def pooled_autocorrelation(series: Sequence[np.ndarray], lag: int) -> float:
    """The autocorrelation at ``lag`` samples of several series pooled (each about its own mean)."""
    num = den = 0.0
    for s in series:
        if len(s) <= lag:
            continue
        c = s - s.mean()
        num += float(np.sum(c[:-lag] * c[lag:])) if lag else float(np.sum(c * c))
        den += float(np.sum(c * c)) * (len(c) - lag) / len(c)
    return num / den if den > 0 else float("nan")


def arrival_velocity_errors(
    t: np.ndarray, x: np.ndarray, y: np.ndarray, vx: np.ndarray, vy: np.ndarray
) -> list[float]:
    """The horizontal velocity error on each arrival (module docstring), in time order.

    ``t`` (s), ``x``, ``y`` (m) and ``vx``, ``vy`` (m/s): the logged (estimated) position and
    velocity over the flight window; an arrival whose window runs past its end is left out.
    """
    if len(t) < 2 or t[-1] - t[0] < 2 * ARRIVAL_WINDOW:
        return []
    ex, ey = velocity_errors(t, x, y, vx, vy, rate=ARRIVAL_RATE)
    g = np.arange(t[0] + 0.5, t[-1] - 0.5, 1.0 / ARRIVAL_RATE)
    err = np.hypot(ex, ey)
    speed = np.hypot(np.interp(g, t, vx), np.interp(g, t, vy))
    out: list[float] = []
    i, n = 0, len(g)
    while i < n:
        fast = np.flatnonzero(speed[i:] > ARRIVAL_FAST)
        if not len(fast):
            break
        j = i + int(fast[0])
        slow = np.flatnonzero(speed[j:] < ARRIVAL_SLOW)
        if not len(slow):
            break
        k = j + int(slow[0])
        window = (g >= g[k]) & (g < g[k] + ARRIVAL_WINDOW)
        if g[k] + ARRIVAL_WINDOW <= g[-1]:
            out.append(float(np.median(err[window])))
        i = k + 1
    return out


BRAKING_WINDOW = (0.0, 3.0)  # s after a waypoint's acceptance: the end of the braking and after


def braking_velocity_errors(
    t: np.ndarray,
    estimate: np.ndarray,
    t_truth: np.ndarray,
    truth: np.ndarray,
    changes: np.ndarray,
    window: tuple[float, float] = BRAKING_WINDOW,
    rate: float = 10.0,
) -> list[tuple[float, float]]:
    """EKF2's horizontal velocity error against the ground truth as the vehicle brakes into a
    waypoint: per leg, the mean over ``window`` seconds after the navigator accepted it (the
    triplet's next change), along the leg and across it (to its right), m/s.

    ``t``, ``estimate``: the logged position and velocity, (N, 4) x, y, vx, vy; ``t_truth``,
    ``truth``: the ground truth's velocity, (M, 2) vx, vy; ``changes``: the setpoint triplet's
    changes (``analysis.ulog.setpoint_changes``). A leg shorter than ``waypoint_passes.LEG_MIN``,
    or whose window runs past either log, is left out.
    """
    out: list[tuple[float, float]] = []
    end = min(t[-1], t_truth[-1]) if len(t) and len(t_truth) else -np.inf
    for k in range(len(changes) - 1):
        start, tx, ty = changes[k][:3]
        accepted = changes[k + 1][0]
        i = int(np.searchsorted(t, start))
        if i >= len(t) or accepted + window[1] > end:
            continue
        leg = np.array([tx - estimate[i, 0], ty - estimate[i, 1]])
        length = float(np.hypot(*leg))
        if length < LEG_MIN:
            continue
        along = leg / length
        right = np.array([-along[1], along[0]])
        g = np.arange(accepted + window[0], accepted + window[1], 1.0 / rate)
        err = errors_on(g, t, estimate[:, 2:], t_truth, truth, 2)
        out.append((float((err @ along).mean()), float((err @ right).mean())))
    return out


def takeoff_turned_back(t: np.ndarray, height: np.ndarray, until: float, drop: float = 1.0) -> bool:
    """Whether the takeoff stalled as PX4 SIH's sometimes do: before ``until`` (s, when the takeoff
    was reached) the height fell ``drop`` metres or more below the highest it had been.

    ``t`` (s) and ``height`` (m, up) over the flight: FlightTaskAuto's target went back to the
    track's start on the ground (``mc_pos_control.Controller.update``) and the vehicle descended.
    """
    h = np.asarray(height)[np.asarray(t) < until]
    return bool(len(h)) and bool(np.any(np.maximum.accumulate(h) - h >= drop))


@dataclass(frozen=True, slots=True)
class PairFigures:
    """How far apart two flights are (module docstring)."""

    dtw: float
    mean_distance: float
    speed_error: float
    altitude_error: float


def compare(a: FlightFigures, b: FlightFigures) -> PairFigures:
    """The pair figures of two measured flights."""
    return PairFigures(
        dtw=dtw_points(a.path, b.path).per_step,
        mean_distance=float(np.linalg.norm(a.path - b.path, axis=1).mean()),
        speed_error=float(np.abs(a.speed - b.speed).mean()),
        altitude_error=float(np.abs(a.path[:, 2] - b.path[:, 2]).mean()),
    )


def pairs_within(flights: Sequence[FlightFigures]) -> list[PairFigures]:
    """Every pair of distinct flights (run vs run of the same simulator)."""
    return [compare(a, b) for a, b in combinations(flights, 2)]


def pairs_between(ours: Sequence[FlightFigures], theirs: Sequence[FlightFigures]) -> list[PairFigures]:
    """Every flight of one set against every flight of the other."""
    return [compare(a, b) for a in ours for b in theirs]


@dataclass(frozen=True, slots=True)
class Spread:
    """Mean, minimum, maximum and standard deviation of one figure over flights or pairs.

    ``std`` is the sample standard deviation (0 for one value): unlike the range, it does not grow
    with the number of flights, so 25 built-in flights and 12 PX4 flights compare on it."""

    mean: float
    low: float
    high: float
    n: int
    std: float = 0.0

    def __str__(self) -> str:
        return f"{self.mean:.2f} ({self.low:.2f}–{self.high:.2f})"

    def inside(self, other: Spread) -> bool:
        """This figure's mean lies within ``other``'s range (at most its maximum)."""
        return self.mean <= other.high


#: standard errors within which a mean is too close to its bound for the verdict to stand: more
#: seeds could turn it either way
NOISE_Z = 2.0


def group_standard_error(values: Sequence[float], groups: int) -> float:
    """The standard error of the mean of ``values`` that come in ``groups`` equal, consecutive,
    independent groups, dependent within: a built-in seed against every PX4 flight, in
    ``pairs_between``'s order (the pairs of one seed share its flight, so they are not independent
    draws, the seeds are). The spread of the groups' means over the root of their number; 0 for
    one group. BadInput when ``values`` do not split into ``groups`` equal groups."""
    n = len(values)
    if groups < 1 or n == 0 or n % groups:
        raise BadInput(f"{n} values do not split into {groups} equal groups")
    if groups == 1:
        return 0.0
    means = np.asarray(values, dtype=np.float64).reshape(groups, n // groups).mean(axis=1)
    return float(means.std(ddof=1) / np.sqrt(groups))


def within_noise(mean: float, error: float, low: float, high: float, z: float = NOISE_Z) -> bool:
    """Whether ``mean`` lies within ``z`` standard errors (``error``) of the bound of [``low``,
    ``high``] that decides whether it is inside (pass ``-inf`` for a one-sided range): then the
    verdict inside / outside is the seeds' luck, not the simulator's. Pure."""
    if mean < low:
        gap = low - mean
    elif mean > high:
        gap = mean - high
    else:
        gap = min(mean - low, high - mean)
    return gap <= z * error


def spread(values: Sequence[float]) -> Spread:
    """Mean, range and standard deviation of ``values``; BadInput when there are none."""
    if not len(values):
        raise BadInput("no values to summarise: at least one flight or pair is needed")
    arr = np.asarray(values, dtype=np.float64)
    std = float(arr.std(ddof=1)) if len(arr) > 1 else 0.0
    return Spread(float(arr.mean()), float(arr.min()), float(arr.max()), len(arr), std)
