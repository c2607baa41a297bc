"""The land detector: no false landing while the takeoff ramp still holds the vehicle on the ground.

PX4's multicopter land detector only lets ground contact count under climb-rate control when a
descent is commanded, so a vehicle whose thrust is still ramping up for takeoff never "lands".
"""

import io
from pathlib import Path

import numpy as np
import pytest

from uavtest.px4.modes import NavState
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.mav import MavCmd, Msg
from uavtest.sitl.recorder import MemorySink

from .conftest import competition
from .test_vehicle import GCS, command, ready_vehicle


def test_mission2_completes_for_every_seed(shared_data: Path):
    """Seeds 25, 30, 41, ... used to see 'Landing detected' ~2 s after takeoff, still on the ground."""
    failed = []
    for seed in range(60):
        config, items = competition(shared_data, 2, seed)
        flight = fly_mission(config, items)
        reached = [seq for seq, _ in flight.reached]
        if reached != list(range(len(items))) or flight.flight_time is None or flight.flight_time < 30:
            failed.append((seed, flight.flight_time, [text for _, text in flight.texts][:6]))
    assert not failed, f"flights that did not complete: {failed}"


@pytest.mark.parametrize("ramp_s", [3.0, 6.0, 10.0])
def test_slow_takeoff_ramp_leaves_the_ground_instead_of_landing(ramp_s: float):
    v = ready_vehicle(params={"MPC_TKO_RAMP_T": ramp_s})
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, float("nan"), float("nan"), float("nan"), 488.0 + 5)
    v.fly_until(lambda v: not v.landed, 20_000_000)
    assert not v.landed, "takeoff was never detected"
    takeoff_us = v.takeoff_us
    v.fly_until(lambda v: not v.body.on_ground or v.landed or not v.armed, 30_000_000)
    assert v.armed and not v.landed, "landing detected while the takeoff ramp held the vehicle down"
    assert v.takeoff_us == takeoff_us
    v.fly_until(lambda v: -v.body.z > 4.0, 30_000_000)
    assert -v.body.z > 4.0


def _landing_from_3m(seed: int):
    """A vehicle taken off to 3 m and told to land (NAV_LAND)."""
    v = ready_vehicle(seed=seed)
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, float("nan"), float("nan"), float("nan"), 488.0 + 3)
    v.fly_until(lambda v: -v.body.z > 2.5, 30_000_000)
    command(v, MavCmd.NAV_LAND)
    return v


def test_landing_is_still_detected_after_a_land_command():
    v = _landing_from_3m(25)
    assert v.nav_state == NavState.AUTO_LAND
    v.fly_until(lambda v: not v.armed, 60_000_000)
    assert v.landed and not v.armed
    assert v.landed_at_us > v.takeoff_us > 0


def test_position_mode_lands_with_throttle_down():
    v = ready_vehicle(params={"COM_DISARM_LAND": 2.0})
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, float("nan"), float("nan"), float("nan"), 488.0 + 3)
    v.fly_until(lambda v: -v.body.z > 2.5, 30_000_000)
    v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}, *GCS))  # needed
    command(v, MavCmd.DO_SET_MODE, 1, 3, 0)  # POSCTL
    assert v.nav_state == NavState.POSCTL

    def sticks_down(v) -> bool:
        v.receive(Msg("MANUAL_CONTROL", {"x": 0, "y": 0, "z": 0, "r": 0, "target": 1}, 255, 190))
        return v.landed

    v.fly_until(sticks_down, 60_000_000)
    assert v.landed


def _px4_descents(shared_data: Path) -> list[float]:
    """PX4 SIH's mission2 landings: the land item reached (descent starts) to landing detected, s."""
    from pyulog import ULog

    out = []
    for path in sorted((shared_data / "px4-sih").glob("competition-mission2-*.ulg")):
        log = ULog(str(path), ["mission_result", "vehicle_land_detected"])
        result = log.get_dataset("mission_result").data
        last = result["seq_reached"].max()
        started = result["timestamp"][result["seq_reached"] == last][0] / 1e6
        detected = log.get_dataset("vehicle_land_detected").data
        landed = detected["timestamp"][(detected["landed"] == 1) & (detected["timestamp"] / 1e6 > started)]
        out.append(landed[0] / 1e6 - started)
    return out


def test_mission_landing_takes_px4_sih_time(shared_data: Path):
    """From 10 m, PX4 v1.15 SIH descends and detects the landing in 14.1-14.6 s: the descent tracks
    the smoothed trajectory's integrated altitude (not its velocity alone, which lags: ~18 s) and the
    land detector's three hysteresis steps of LNDMC_TRIG_TIME / 3 follow the touchdown. EKF2's
    vertical velocity error (0.12 m/s) holds the vehicle a little above or below the profile, so
    the crawl of the last metre takes a few tenths of a second more or less (PX4 mission1: 14.6-15.5 s)."""
    px4 = _px4_descents(shared_data)
    assert len(px4) == 4
    low, high = min(px4) - 1.5, max(px4) + 1.5
    ours = []
    for seed in range(16):
        config, items = competition(shared_data, 2, seed)
        flight = fly_mission(config, items)
        started = next(t for seq, t in flight.reached if seq == len(items) - 1)
        assert flight.landed_s is not None
        ours.append(flight.landed_s - started)
    # EKF2's altitude drifts in flight (the true height where the descent starts is decimetres off
    # the estimate's 10 m) and shifts after touchdown, which delays some landings: the 8 PX4 SIH
    # mission2 flights flown here (2026-11-27) land in 14.1-24.3 s, 4 of them within 1.5 s of the
    # shared logs' range. The built-in's share is about as large (32 seeds: 18 quick, stop 38's tree
    # 16); 16 seeds, not 8, so that one unlucky draw of 8 (3 quick on seeds 0-7 at stop 39) does
    # not decide it
    quick = [d for d in ours if low <= d <= high]
    assert len(quick) >= 6, f"PX4 {px4}, built-in {ours}"
    assert all(low <= d <= high + 10.0 for d in ours), f"PX4 {px4}, built-in {ours}"


def test_no_landing_is_detected_in_the_air_and_it_follows_touchdown_by_px4s_hysteresis():
    v = _landing_from_3m(3)
    v.est.ground_shift = 0.0  # no EKF2 shift after touchdown (see the tests below)
    seen_landed_in_air = []

    def touched(v) -> bool:
        if v.landed:
            seen_landed_in_air.append(v.time_us)
        return v.body.on_ground

    v.fly_until(touched, 60_000_000)
    assert v.body.on_ground and not seen_landed_in_air and not v.landed
    touchdown = v.time_us
    v.fly_until(lambda v: v.landed, 10_000_000)
    # three steps of LNDMC_TRIG_TIME / 3 after the thrust has fallen (0.35-0.75 s after touchdown)
    assert 1.3 <= (v.landed_at_us - touchdown) / 1e6 <= 1.8


def test_no_landing_while_the_estimate_still_moves():
    """MulticopterLandDetector judges vertical movement on EKF2's estimate: a vehicle resting on
    the ground whose estimate still climbs at 0.3 m/s (LNDMC_Z_VEL_MAX 0.25) is not landed; it is
    once the estimate settles. PX4 v1.15 SIH shows this after hard touchdowns (up to 9.7 s)."""
    v = _landing_from_3m(25)
    v.est.ground_shift = 0.0
    v.fly_until(lambda v: v.body.on_ground, 60_000_000)
    assert not v.landed
    e = v.est
    touchdown = v.time_us
    held_until = touchdown + 5_000_000
    while v.time_us < held_until:  # EKF2 believes the vehicle climbs: climb rate and altitude
        e._cvz, e.bz = -0.3, 0.0
        v.advance(v.time_us + 20_000)
        assert not v.landed, f"landed {(v.time_us - touchdown) / 1e6:.1f} s after touchdown while moving"
    v.fly_until(lambda v: v.landed, 10_000_000)
    # the range finder has not been fused for 5 s: EKF2's terrain estimate is invalid and each
    # land-detector stage takes the full LNDMC_TRIG_TIME (1 s)
    assert v.landed and 3_000_000 <= v.landed_at_us - held_until < 4_000_000


def _touchdown_with_shift(shift: float):
    v = _landing_from_3m(25)
    v.est.ground_shift = shift
    v.fly_until(lambda v: v.body.on_ground, 60_000_000)
    assert not v.landed
    touchdown = v.time_us
    stages: dict[str, float] = {}

    def landed(v) -> bool:  # each stage's last rise: a brief contact at touchdown starts over
        for name in ("ground_contact", "maybe_landed"):
            if not getattr(v, name):
                stages.pop(name, None)
            elif name not in stages:
                stages[name] = v.time_us
        return v.landed

    v.fly_until(landed, 20_000_000)
    assert v.landed
    return v, (v.landed_at_us - touchdown) / 1e6, {k: (v.landed_at_us - t) / 1e6 for k, t in stages.items()}


def test_ekf2s_climb_after_touchdown_delays_the_landing_as_in_px4_sih():
    """PX4 v1.15 SIH, 16 flights flown here: when EKF2's altitude shifts by about a metre after
    touchdown (the range finder reads below its minimum, the baro/GNSS height takes over), the
    estimate climbs at 0.3-0.5 m/s and its distance to the ground passes 1 m; the land detector
    waits until the terrain estimate times out (5 s) and then takes LNDMC_TRIG_TIME per stage:
    landed 8.2-9.5 s after touchdown, ground_contact 2.0 s and maybe_landed 1.0 s before it."""
    v, after, stages = _touchdown_with_shift(-1.3)
    assert 7.5 <= after <= 9.5
    assert stages["ground_contact"] == pytest.approx(2.0, abs=0.3)
    assert stages["maybe_landed"] == pytest.approx(1.0, abs=0.3)
    assert v.est.z_shift == pytest.approx(-1.3, abs=0.01)  # the estimate stays where it went


def test_a_small_shift_after_touchdown_does_not_delay_the_landing():
    """PX4 SIH: shifts of 0.6 m or less (11 of 16 flights) landed 1.4-2.8 s after touchdown."""
    for shift in (-0.5, 0.0, 0.5):
        _, after, _ = _touchdown_with_shift(shift)
        assert 1.3 <= after <= 2.0, f"shift {shift} m: landed {after:.1f} s after touchdown"


def _stages(log) -> tuple[float, float]:
    """vehicle_land_detected's last landing: ground contact and maybe landed, s before landed."""
    d = log.get_dataset("vehicle_land_detected").data
    t = d["timestamp"] / 1e6
    landed_at = t[np.flatnonzero((d["landed"][1:] == 1) & (d["landed"][:-1] == 0))[-1] + 1]

    def since(field: str) -> float:
        rises = np.flatnonzero((d[field][1:] == 1) & (d[field][:-1] == 0)) + 1
        return landed_at - t[rises[t[rises] <= landed_at][-1]]

    return since("ground_contact"), since("maybe_landed")


def test_the_log_shows_the_land_detectors_stages_as_px4_publishes_them(shared_data: Path):
    """PX4's land detector publishes vehicle_land_detected whenever ground contact or maybe landed
    changes, so a PX4 log shows the stages: ground contact 0.7 s and maybe landed 0.3 s before
    landed (LNDMC_TRIG_TIME / 3 each). The built-in log published only on landed or at 1 Hz."""
    from pyulog import ULog

    px4 = [_stages(ULog(str(p))) for p in sorted((shared_data / "px4-sih").glob("competition-mission*.ulg"))]
    config, items = competition(shared_data, 2, 0)
    sink = MemorySink()
    fly_mission(config, items, sink=sink)
    contact, maybe = _stages(ULog(io.BytesIO(sink.logs[0])))
    assert min(c for c, _ in px4) - 0.05 <= contact <= max(c for c, _ in px4) + 0.05, (px4, contact)
    assert min(m for _, m in px4) - 0.05 <= maybe <= max(m for _, m in px4) + 0.05, (px4, maybe)
