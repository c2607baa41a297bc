"""Body rates as PX4 reports them: ATTITUDE / ATTITUDE_QUATERNION / ODOMETRY rollspeed, pitchspeed,
yawspeed and HIGHRES_IMU's gyro carry ``vehicle_angular_velocity`` (PX4 v1.15 streams/ATTITUDE.hpp
and friends), and the ULog logs that topic. They are the rates of the attitude the vehicle reports,
not zeros: a MAVSDK ``telemetry.attitude_angular_velocity_body()`` user sees the vehicle roll."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from pyulog import ULog

from uavtest.sitl.mav import MavCmd, Msg
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig, Vehicle

GCS = (255, 190)


def _command(v: Vehicle, cmd: int, *params: float) -> list[Msg]:
    fields: dict[str, object] = {"command": int(cmd), "target_system": 1, "target_component": 1}
    fields.update({f"param{i}": p for i, p in enumerate(params, start=1)})
    return v.receive(Msg("COMMAND_LONG", fields, *GCS))


def _euler_rates_to_body(roll, pitch, droll, dpitch, dyaw):
    return (
        droll - dyaw * np.sin(pitch),
        dpitch * np.cos(roll) + dyaw * np.sin(roll) * np.cos(pitch),
        -dpitch * np.sin(roll) + dyaw * np.cos(roll) * np.cos(pitch),
    )


def _fly_a_turning_leg(sink: MemorySink | None = None) -> tuple[Vehicle, list[dict]]:
    """Take off, then reposition 22 m north and 15 m east: the vehicle yaws toward it, leans
    into the leg and brakes at its end. Every ATTITUDE message of that leg."""
    v = Vehicle(SimConfig(seed=5), sink=sink)
    v.fly_until(lambda v: v.ready, 5_000_000)
    _command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    _command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, v.home_alt + 6)
    v.fly_until(lambda v: v.st.z < -5.5, 30_000_000)
    home = v.config.home
    _command(v, MavCmd.DO_REPOSITION, -1, 1, 0, math.nan, home.lat + 0.0002, home.lon + 0.0002, math.nan)
    att = []
    end = v.time_us + 15_000_000
    while v.time_us < end:
        att += [m.fields for m in v.advance(v.time_us + 20_000) if m.name == "ATTITUDE"]
    return v, att


def test_attitude_reports_the_body_rates_of_the_attitude_it_reports():
    _, att = _fly_a_turning_leg()
    t = np.array([a["time_boot_ms"] for a in att]) / 1e3
    roll, pitch = (np.array([a[k] for a in att]) for k in ("roll", "pitch"))
    yaw = np.unwrap([a["yaw"] for a in att])
    dt = np.diff(t)
    mid = lambda a: (a[1:] + a[:-1]) / 2  # noqa: E731 - the rate between two samples
    expected = _euler_rates_to_body(
        mid(roll), mid(pitch), np.diff(roll) / dt, np.diff(pitch) / dt, np.diff(yaw) / dt
    )
    for axis, key in enumerate(("rollspeed", "pitchspeed", "yawspeed")):
        reported = mid(np.array([a[key] for a in att]))
        want = expected[axis]
        assert np.sqrt(np.mean(want**2)) > 0.02, key  # the leg rolls, pitches and yaws
        assert np.corrcoef(reported, want)[0, 1] > 0.8, key
        assert np.sqrt(np.mean(reported**2)) == pytest.approx(np.sqrt(np.mean(want**2)), rel=0.3), key


def test_every_rate_message_and_the_log_carry_the_same_body_rates():
    sink = MemorySink()
    v, _ = _fly_a_turning_leg(sink)
    by = {}
    for _ in range(50):  # one 50 Hz tick that carries them all
        by = {m.name: m.fields for m in v.advance(v.time_us + 20_000)}
        if {"ATTITUDE", "ATTITUDE_QUATERNION", "ODOMETRY", "HIGHRES_IMU"} <= by.keys():
            break
    rates = (by["ATTITUDE"]["rollspeed"], by["ATTITUDE"]["pitchspeed"], by["ATTITUDE"]["yawspeed"])
    for name in ("ATTITUDE_QUATERNION", "ODOMETRY"):
        assert (by[name]["rollspeed"], by[name]["pitchspeed"], by[name]["yawspeed"]) == pytest.approx(rates)
    imu = by["HIGHRES_IMU"]
    assert (imu["xgyro"], imu["ygyro"], imu["zgyro"]) == pytest.approx(rates)
    v.recorder.stop()
    log = ULog(io.BytesIO(sink.logs[0]))
    av = log.get_dataset("vehicle_angular_velocity").data
    att = log.get_dataset("vehicle_attitude").data
    assert np.array_equal(av["timestamp"], att["timestamp"])  # logged with the attitude, 25 Hz
    flying = av["timestamp"] > av["timestamp"][-1] - 15_000_000
    p = av["xyz[0]"][flying]
    assert np.sqrt(np.mean(p**2)) > 0.02
    # xyz_derivative: the change of the rates between two samples
    dt = np.diff(av["timestamp"]) / 1e6
    assert av["xyz_derivative[0]"][1:] == pytest.approx(np.diff(av["xyz[0]"]) / dt, rel=1e-3, abs=1e-3)


def test_at_rest_on_the_ground_the_rates_are_zero():
    v = Vehicle(SimConfig(seed=5))
    v.fly_until(lambda v: v.ready, 5_000_000)
    att = [m.fields for m in v.advance(v.time_us + 1_000_000) if m.name == "ATTITUDE"]
    assert att
    for a in att:
        assert (a["rollspeed"], a["pitchspeed"], a["yawspeed"]) == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
