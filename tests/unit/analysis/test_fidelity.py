"""The fidelity figures: flights measured from lift-off on normalised time."""

from __future__ import annotations

import numpy as np
import pytest

from uavtest.analysis.fidelity import (
    NORMALISED_POINTS,
    altitude_drift,
    arrival_velocity_errors,
    body_frame_errors,
    boot_time_correlation,
    braking_velocity_errors,
    compare,
    estimate_errors,
    estimate_lead,
    flight_figures,
    from_liftoff,
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
from uavtest.analysis.trajectory import Trajectory
from uavtest.errors import BadInput


def flight(
    duration: float = 40.0,
    *,
    shift: tuple[float, float, float] = (0, 0, 0),
    rate: float = 50.0,
    noise: float = 0.0,
    cruise: float = 10.0,
    seed: int = 0,
) -> Trajectory:
    """2 s on the ground, climb to ``cruise`` m at 2 m/s, fly north at constant speed, descend."""
    t = np.arange(0.0, duration, 1.0 / rate)
    climb_end = 2.0 + cruise / 2.0
    descend_start = duration - cruise / 2.0 - 1.0
    alt = np.clip(np.minimum((t - 2.0) * 2.0, (duration - 1.0 - t) * 2.0), 0.0, cruise)
    x = np.clip((t - climb_end) / (descend_start - climb_end), 0.0, 1.0) * 50.0
    rng = np.random.default_rng(seed)
    x = x + noise * rng.standard_normal(len(t))
    return Trajectory(t + 100.0, x + shift[0], np.zeros_like(t) + shift[1], -alt + shift[2])


def test_from_liftoff_starts_at_the_lift_off_point_and_time():
    f = from_liftoff(flight(shift=(5.0, -3.0, -1.0)))  # the estimate sits 1 m off the ground
    assert f.t[0] == 0.0
    assert (f.x[0], f.y[0]) == (0.0, 0.0)
    assert -f.z[0] == pytest.approx(0.3, abs=0.05)  # lifted off: 0.3 m above where it stood
    assert f.duration == pytest.approx(40.0 - 2.0 - 0.15 - 0.02, abs=0.05)


def test_from_liftoff_refuses_a_flight_that_never_climbed():
    t = np.arange(0.0, 10.0, 0.1)
    with pytest.raises(BadInput, match="lift-off"):
        from_liftoff(Trajectory(t, t * 0, t * 0, t * 0))


def test_the_same_flight_offset_in_space_and_time_compares_as_equal():
    a = flight_figures(flight())
    b = flight_figures(flight(shift=(2.0, 1.0, -0.8)))
    p = compare(a, b)
    assert p.dtw < 1e-6 and p.mean_distance < 1e-6 and p.speed_error < 1e-6 and p.altitude_error < 1e-6
    assert a.path.shape == (NORMALISED_POINTS, 3)


def test_a_slower_flight_of_the_same_path_differs_in_time_not_in_shape():
    a = flight_figures(flight(40.0))
    b = flight_figures(flight(50.0))
    p = compare(a, b)
    assert b.flight_time - a.flight_time == pytest.approx(10.0, abs=0.1)
    assert p.dtw < 0.5 * p.mean_distance  # DTW forgives the timing, the equal-time distance does not
    assert p.speed_error > 0.1


def test_a_lower_cruise_shows_as_altitude_error():
    p = compare(flight_figures(flight()), flight_figures(flight(cruise=8.0)))
    assert p.altitude_error > 1.0


def test_white_noise_on_the_position_shows_as_jitter():
    smooth = flight_figures(flight())
    noisy = flight_figures(flight(noise=0.05))
    assert smooth.jitter < 0.15  # only the speed steps of the synthetic flight
    assert noisy.jitter > smooth.jitter + 0.3


def test_pairs_and_spread():
    flights = [flight_figures(flight(40.0 + k)) for k in range(3)]
    assert len(pairs_within(flights)) == 3
    assert len(pairs_between(flights, flights[:2])) == 6
    s = spread([1.0, 2.0, 4.0])
    assert (s.mean, s.low, s.high, s.n) == (pytest.approx(7 / 3), 1.0, 4.0, 3)
    assert s.inside(spread([0.5, 2.5])) and not s.inside(spread([0.5, 2.0]))
    # the sample standard deviation: comparable between 25 flights and 12, unlike the range
    assert s.std == pytest.approx(float(np.std([1.0, 2.0, 4.0], ddof=1)))
    assert spread([3.0]).std == 0.0
    with pytest.raises(BadInput):
        spread([])


def test_a_built_in_vs_px4_mean_is_as_certain_as_its_seeds_not_its_pairs():
    # three seeds, each against four PX4 flights: a seed's four pairs share its one flight
    values = [1.0] * 4 + [2.0] * 4 + [3.0] * 4
    error = group_standard_error(values, 3)
    assert error == pytest.approx(1.0 / np.sqrt(3.0))  # the seeds' means 1, 2, 3
    # twelve independent draws would claim less than half that
    assert float(np.std(values, ddof=1) / np.sqrt(12)) < 0.5 * error
    assert group_standard_error([2.0, 4.0], 1) == 0.0  # one seed: nothing to tell the spread by
    with pytest.raises(BadInput, match="10 values do not split into 3 equal groups"):
        group_standard_error([1.0] * 10, 3)


def test_a_verdict_within_two_standard_errors_of_its_bound_is_the_seeds_luck():
    inf = float("inf")
    # mission1's mean distance at stop 43: 2.51 +- 0.30 against PX4's 2.76: inside, by luck
    assert within_noise(2.51, 0.30, -inf, 2.76)
    # its path shape: 0.60 +- 0.04 against 0.47, outside beyond doubt
    assert not within_noise(0.60, 0.04, -inf, 0.47)
    # a flight time, two-sided: the nearer bound decides
    assert within_noise(42.66, 1.27, 38.02, 43.80)
    assert not within_noise(40.0, 0.5, 38.0, 43.8)
    assert within_noise(37.5, 0.3, 38.0, 43.8) and not within_noise(37.0, 0.3, 38.0, 43.8)


def _leg_and_stop(bias_after_stop: tuple[float, float]) -> tuple[np.ndarray, ...]:
    """A 50 m leg North at 5 m/s, a stop, 10 s of hover; the logged velocity carries ``bias``
    once stopped while the position does not move (EKF2's velocity error)."""
    t = np.arange(0.0, 30.0, 0.02)
    vx = np.where(t < 10.0, 5.0, np.where(t < 12.0, 5.0 * (12.0 - t) / 2.0, 0.0))
    x = np.cumsum(vx) * 0.02
    y = np.zeros_like(t)
    bx, by = bias_after_stop
    est_vx = vx + np.where(t >= 12.0, bx, 0.0)
    est_vy = np.where(t >= 12.0, by, 0.0)
    return t, x, y, est_vx, est_vy


def test_arrival_velocity_error_is_the_logged_velocity_against_the_positions_own_motion():
    errors = arrival_velocity_errors(*_leg_and_stop((0.3, 0.4)))
    assert errors == [pytest.approx(0.5, abs=0.02)]
    assert arrival_velocity_errors(*_leg_and_stop((0.0, 0.0))) == [pytest.approx(0.0, abs=0.02)]


def test_no_leg_no_arrival():
    t = np.arange(0.0, 20.0, 0.02)
    hover = np.zeros_like(t)
    assert arrival_velocity_errors(t, hover, hover, hover + 0.5, hover) == []
    assert arrival_velocity_errors(t[:10], hover[:10], hover[:10], hover[:10], hover[:10]) == []


def test_velocity_errors_see_a_velocity_the_position_does_not_follow():
    t = np.arange(0.0, 20.0, 0.02)
    x = 2.0 * t  # flying North at 2 m/s
    y = np.zeros_like(t)
    ex, ey = velocity_errors(t, x, y, np.full_like(t, 2.3), np.full_like(t, -0.1))
    assert np.allclose(ex, 0.3) and np.allclose(ey, -0.1)
    assert [len(e) for e in velocity_errors(t[:50], x[:50], y[:50], x[:50], y[:50])] == [0, 0]


def test_pooled_autocorrelation_of_a_slow_and_a_white_process():
    rng = np.random.default_rng(1)
    white = [rng.normal(size=5000) for _ in range(3)]
    slow = [np.convolve(w, np.ones(50) / 50, mode="valid") for w in white]
    assert abs(pooled_autocorrelation(white, 10)) < 0.05
    assert pooled_autocorrelation(slow, 10) == pytest.approx(0.8, abs=0.05)  # 40/50 overlap
    assert pooled_autocorrelation(slow, 0) == pytest.approx(1.0)


def test_estimate_errors_against_px4_sihs_ground_truth(square_log) -> None:
    """square-mission.ulg logs EKF2's estimate and SIH's truth: the position is off by about a
    quarter metre per axis (about its mean: the EKF origin is not SIH's), the velocity by 0.2 m/s."""
    lp = square_log.get_dataset("vehicle_local_position").data
    gt = square_log.get_dataset("vehicle_local_position_groundtruth").data
    cols = ("x", "y", "vx", "vy")
    pos, vel = estimate_errors(
        lp["timestamp"] / 1e6,
        np.column_stack([lp[k] for k in cols]),
        gt["timestamp"] / 1e6,
        np.column_stack([gt[k] for k in cols]),
        (136.5, 176.0),
    )
    assert 0.15 < pos < 0.35 and 0.12 < vel < 0.3
    # the truth against itself: no error
    same = estimate_errors(
        gt["timestamp"] / 1e6,
        np.column_stack([gt[k] for k in cols]),
        gt["timestamp"] / 1e6,
        np.column_stack([gt[k] for k in cols]),
        (136.5, 176.0),
    )
    assert same == pytest.approx((0.0, 0.0), abs=1e-9)


def _truth_track() -> tuple[np.ndarray, np.ndarray]:
    """Accelerate north to 4 m/s, cruise, brake: (t, truth columns x, y, vx, vy) at 50 Hz."""
    t = np.arange(0.0, 30.0, 0.02)
    vx = np.clip(np.minimum(t - 2.0, 26.0 - t), 0.0, 4.0)
    x = np.cumsum(vx) * 0.02
    return t, np.column_stack([x, np.zeros_like(t), vx, np.zeros_like(t)])


def test_estimate_lead_recovers_a_lead_and_ignores_a_drifting_offset() -> None:
    t, truth = _truth_track()
    drift = 0.3 + 0.01 * t  # a slow offset is not a lead
    estimate = np.column_stack([truth[:, 0] + 0.1 * truth[:, 2] + drift, truth[:, 1]])
    assert estimate_lead(t, estimate, t, truth, (1.0, 29.0)) == pytest.approx(0.1, abs=0.01)
    assert estimate_lead(t, truth[:, :2], t, truth, (1.0, 29.0)) == pytest.approx(0.0, abs=1e-9)


def test_estimate_lead_refuses_what_cannot_tell_it() -> None:
    t, truth = _truth_track()
    with pytest.raises(BadInput, match="shorter than the span"):
        estimate_lead(t, truth[:, :2], t, truth, (10.0, 10.5))
    with pytest.raises(BadInput, match="never changed"):  # cruising only: no change of velocity
        estimate_lead(t, truth[:, :2], t, truth, (10.0, 20.0))


def test_body_frame_errors_turn_the_error_with_the_heading() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 60.0, 0.1)
    fore, side = 0.1 * rng.standard_normal(len(t)), 0.3 * rng.standard_normal(len(t))
    yaw = np.where(t < 30.0, 0.0, np.pi / 2)  # north, then east
    c, s = np.cos(yaw), np.sin(yaw)
    truth = np.column_stack([np.full_like(t, 2.0), np.zeros_like(t)])
    estimate = np.column_stack([truth + np.column_stack([c * fore - s * side, s * fore + c * side]), yaw])
    got = body_frame_errors(t, estimate, t, truth, (0.0, 59.9))
    assert got == (pytest.approx(fore.std(), rel=0.05), pytest.approx(side.std(), rel=0.05))
    # judged in NED instead, north and east each mix both halves: no axis stands out
    assert np.std(estimate[:, 0] - 2.0) == pytest.approx(np.std(estimate[:, 1]), rel=0.2)
    with pytest.raises(BadInput, match="empty"):
        body_frame_errors(t, estimate, t, truth, (5.0, 5.0))


def test_boot_time_correlation_tells_one_noise_realization_from_independent_ones() -> None:
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 60.0, 0.1)
    shared = np.convolve(rng.standard_normal(len(t) + 20), np.ones(20) / 20, mode="valid")[: len(t)]
    # PX4 SIH: the same noise sequence, shifted a little by scheduling, plus a little of its own
    same = [(t, np.roll(shared, k) + 0.05 * rng.standard_normal(len(t))) for k in (0, 3, 7, 12)]
    independent = [
        (t, np.convolve(rng.standard_normal(len(t) + 20), np.ones(20) / 20, mode="valid")[: len(t)])
        for _ in range(4)
    ]
    assert boot_time_correlation(same) > 0.8
    assert boot_time_correlation(independent) < 0.45
    with pytest.raises(BadInput, match="at least two"):
        boot_time_correlation(same[:1])
    with pytest.raises(BadInput, match="overlap"):
        boot_time_correlation([(t, shared), (t + 100.0, shared)])


def test_flights_share_their_noise_when_their_errors_are_alike_at_equal_time_since_start() -> None:
    rng = np.random.default_rng(11)
    t = np.arange(0.0, 60.0, 0.1)

    def smooth() -> np.ndarray:
        return np.convolve(rng.standard_normal(len(t) + 20), np.ones(20) / 20, mode="valid")[: len(t)]

    sx, sy = smooth(), smooth()
    same_x = [(t, np.roll(sx, k) + 0.05 * rng.standard_normal(len(t))) for k in (0, 4, 9)]
    same_y = [(t, np.roll(sy, k) + 0.05 * rng.standard_normal(len(t))) for k in (0, 4, 9)]
    own_x = [(t, smooth()) for _ in range(3)]
    own_y = [(t, smooth()) for _ in range(3)]
    assert share_noise(same_x, same_y)
    assert not share_noise(own_x, own_y)


def _vertical_truth() -> tuple[np.ndarray, np.ndarray]:
    """On the ground 5 s, climb to 10 m at 1 m/s, hold, descend at 1 m/s, 20 s on the ground:
    (t, truth columns z, vz) at 50 Hz."""
    t = np.arange(0.0, 130.0, 0.02)
    h = np.clip(np.minimum(t - 5.0, 110.0 - t), 0.0, 10.0)
    vz = -np.gradient(h, t)
    return t, np.column_stack([-h, vz])


def test_vertical_estimate_errors_keep_the_fast_wander_and_leave_out_the_drift_and_the_ground() -> None:
    t, truth = _vertical_truth()
    rng = np.random.default_rng(3)
    # a 0.1 m wander correlated over about 1 s (a 1 s moving mean of white noise, rescaled)
    wander = np.convolve(rng.normal(0.0, 1.0, len(t)), np.ones(50) / 50, mode="same")
    wander *= 0.1 / wander.std()
    drift = 0.6 * np.sin(2 * np.pi * t / 120.0)  # EKF2's slow GNSS/baro drift: left out
    climb_error = rng.normal(0.0, 0.15, len(t))
    ground = np.where(t > 110.0, 1.5, 0.0)  # the estimate's shift after touchdown: left out
    estimate = truth + np.column_stack([wander + drift + ground, climb_error])
    alt, climb = vertical_estimate_errors(t, estimate, t, truth, (0.0, 120.0))
    assert alt == pytest.approx(0.1, abs=0.015)
    assert climb == pytest.approx(0.15, abs=0.01)
    assert vertical_estimate_errors(t, truth, t, truth, (0.0, 120.0)) == pytest.approx((0.0, 0.0), abs=1e-9)


def test_vertical_estimate_errors_need_a_flight_in_the_window() -> None:
    t, truth = _vertical_truth()
    with pytest.raises(BadInput, match="never flew"):
        vertical_estimate_errors(t, truth, t, truth, (111.0, 130.0))
    with pytest.raises(BadInput, match="shorter than the trend"):
        vertical_estimate_errors(t, truth, t, truth, (20.0, 25.0))


def test_vertical_estimate_errors_against_px4_sihs_ground_truth(square_log) -> None:
    """PX4 v1.15 SIH's altitude estimate wanders about a decimetre around the truth in flight
    (GNSS altitude noise 0.5 m, baro 1 Pa in SIH's sensor simulators), its climb rate 0.1-0.2 m/s."""
    lp = square_log.get_dataset("vehicle_local_position").data
    gt = square_log.get_dataset("vehicle_local_position_groundtruth").data
    alt, climb = vertical_estimate_errors(
        lp["timestamp"] / 1e6,
        np.column_stack([lp["z"], lp["vz"]]),
        gt["timestamp"] / 1e6,
        np.column_stack([gt["z"], gt["vz"]]),
        (136.5, 176.0),
    )
    assert 0.05 < alt < 0.2 and 0.08 < climb < 0.25


def test_altitude_drift_keeps_the_slow_drift_and_leaves_out_the_ground() -> None:
    """The spread of the altitude error within a flight, its slow drift kept: a 0.6 m sine over the
    flight measures 0.6 / sqrt(2); the estimate's shift on the ground after touchdown does not
    count; a perfect estimate measures 0."""
    t, truth = _vertical_truth()
    drift = 0.6 * np.sin(2 * np.pi * (t - 15.0) / 40.0)  # whole periods in the flying part
    ground = np.where(t > 110.0, 1.5, 0.0)
    z = truth[:, 0] + drift + ground
    flying = -truth[:, 0] > 1.0
    assert altitude_drift(t, z, t, truth[:, 0], (0.0, 130.0)) == pytest.approx(drift[flying].std(), rel=1e-3)
    assert 0.35 < altitude_drift(t, z, t, truth[:, 0], (0.0, 130.0)) < 0.5
    assert altitude_drift(t, truth[:, 0], t, truth[:, 0], (0.0, 130.0)) == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(BadInput, match="never flew"):
        altitude_drift(t, z, t, truth[:, 0], (111.0, 130.0))


def test_altitude_drift_against_px4_sihs_ground_truth(square_log) -> None:
    """PX4 v1.15 SIH's altitude estimate drifts from the truth by decimetres within a flight
    (EKF2_HGT_REF GNSS: SIH's GNSS altitude noise 0.5 m at 8 Hz): the shared square log 0.17 m; the
    PX4 flights flown here 0.10-0.93 m (median 0.38)."""
    lp = square_log.get_dataset("vehicle_local_position").data
    gt = square_log.get_dataset("vehicle_local_position_groundtruth").data
    drift = altitude_drift(lp["timestamp"] / 1e6, lp["z"], gt["timestamp"] / 1e6, gt["z"], (136.5, 176.0))
    assert 0.1 < drift < 0.3


def test_a_takeoff_that_went_back_down_is_told_from_one_that_climbed_on() -> None:
    """PX4 SIH mission3 replica 6 (flown here): up to 8.9 m, back to the ground, up again, all
    before the takeoff was reached; a climb that wobbles by less than a metre is no stall."""
    t = np.arange(0.0, 30.0, 0.5)
    stall = np.interp(t, [0, 8, 15, 20, 28], [0.0, 8.9, 0.2, 0.2, 9.6])
    assert takeoff_turned_back(t, stall, until=28.5)
    assert not takeoff_turned_back(t, stall, until=8.0)  # reached before it turned back
    wobble = np.interp(t, [0, 6, 7, 12], [0.0, 6.0, 5.3, 9.6])
    assert not takeoff_turned_back(t, wobble, until=12.5)
    assert not takeoff_turned_back(t, wobble, until=-1.0)  # nothing before it


def test_braking_velocity_errors_are_taken_along_and_across_each_leg_after_its_acceptance():
    # a leg east from (0, 0) to (0, 20), accepted at t = 10 s, then a leg back west (accepted at
    # 25 s); the estimate's velocity 0.2 m/s short of the truth eastwards and 0.1 m/s south of
    # it during the 3 s after the first acceptance, right on it otherwise
    t = np.arange(0.0, 30.0, 0.02)
    truth = np.column_stack([np.zeros_like(t), np.ones_like(t)])
    estimate = np.column_stack([np.zeros_like(t), t, truth])
    window = (t >= 10.0) & (t < 13.0)
    estimate[window, 3] -= 0.2
    estimate[window, 2] -= 0.1
    changes = np.array([[0.0, 0.0, 20.0, 0.5], [10.0, 0.0, 0.0, 0.5], [25.0, 0.0, 20.0, 0.5]])
    (along, across), *rest = braking_velocity_errors(t, estimate, t, truth, changes)
    assert along == pytest.approx(-0.2, abs=0.01)
    assert across == pytest.approx(0.1, abs=0.01)  # south is to the right of an eastward leg
    assert rest == [(pytest.approx(0.0), pytest.approx(0.0))]  # the second leg: no error
    # a leg whose window runs past the log is left out
    late = np.array([changes[0], [28.5, 0.0, 0.0, 0.5]])
    assert braking_velocity_errors(t, estimate, t, truth, late) == []
