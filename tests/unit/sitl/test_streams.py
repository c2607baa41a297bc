"""Telemetry per link (PX4 v1.15 mavlink_main.cpp configure_streams_to_default, px4-rc.mavlink),
SET/GET_MESSAGE_INTERVAL per link, the new messages' values, SYSTEM_TIME, honest capabilities and
the generic UNSUPPORTED path, on the in-process vehicle."""

from __future__ import annotations

import math
from collections import Counter

import pytest

from uavtest.sitl.mav import MavCmd, MavResult, Msg
from uavtest.sitl.mavlink_streams import autopilot_version, isa_pressure_hpa
from uavtest.sitl.telemetry import MODES, NORMAL, ONBOARD
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import Wind

GCS = (255, 190)
TWO_LINKS = (("api", ONBOARD), ("gcs", "sitl_gcs"))


def _vehicle(**kw) -> Vehicle:
    return Vehicle(SimConfig(links=TWO_LINKS, seed=1, **kw))


def _command(v: Vehicle, cmd: int, *params: float, link: int = 0) -> list[Msg]:
    fields: dict[str, object] = {"command": int(cmd), "target_system": 1, "target_component": 1}
    fields.update({f"param{i}": p for i, p in enumerate(params, start=1)})
    return v.receive(Msg("COMMAND_LONG", fields, *GCS), link)


def _counts(v: Vehicle, seconds: float) -> list[Counter]:
    counts = [Counter(), Counter()]
    end = v.time_us + int(seconds * 1e6)
    while v.time_us < end:
        v.advance(v.time_us + 100_000, drain=False)
        for c, msgs in zip(counts, v.drain_links(), strict=True):
            c.update(m.name for m in msgs)
    return counts


def test_each_link_streams_its_modes_rates():
    v = _vehicle()
    v.fly_until(lambda v: v.ready, 5_000_000)
    api, gcs = _counts(v, 10.0)
    onboard, sitl_gcs = MODES[ONBOARD], MODES["sitl_gcs"]
    news_only = {"DISTANCE_SENSOR", "OBSTACLE_DISTANCE"}  # no range sensor here: never sent
    for name, hz in onboard.items():
        assert api[name] == (pytest.approx(min(hz, 50.0) * 10, abs=2) if name not in news_only else 0), name
    for name, hz in sitl_gcs.items():
        assert gcs[name] == (pytest.approx(hz * 10, abs=2) if name not in news_only else 0), name
    # ONBOARD-only messages stay off the GCS link (NORMAL has no HIGHRES_IMU, ODOMETRY, SYSTEM_TIME)
    assert gcs["HIGHRES_IMU"] == gcs["ODOMETRY"] == gcs["SYSTEM_TIME"] == 0
    assert MODES[NORMAL]["ATTITUDE"] == 15.0 and sitl_gcs["ATTITUDE"] == 50.0  # px4-rc.mavlink -r 50


def test_a_message_due_on_both_links_is_built_once():
    v = _vehicle()
    v.fly_until(lambda v: v.ready, 5_000_000)
    v.advance(v.time_us + 1_000_000, drain=False)
    api, gcs = v.drain_links()
    shared = {id(m) for m in api if m.name == "ATTITUDE"} & {id(m) for m in gcs if m.name == "ATTITUDE"}
    assert shared  # the same Msg object went to both links


def test_set_message_interval_changes_only_the_link_it_came_from():
    v = _vehicle()
    v.fly_until(lambda v: v.ready, 5_000_000)
    ack = _command(v, MavCmd.SET_MESSAGE_INTERVAL, 141, 500_000, link=1)[0]  # ALTITUDE 2 Hz on GCS
    assert ack.fields["result"] == MavResult.ACCEPTED
    ack = _command(v, MavCmd.SET_MESSAGE_INTERVAL, 331, -1, link=0)[0]  # ODOMETRY off on API
    assert ack.fields["result"] == MavResult.ACCEPTED
    v.drain_links()
    api, gcs = _counts(v, 10.0)
    assert gcs["ALTITUDE"] == pytest.approx(20, abs=1) and api["ALTITUDE"] == pytest.approx(100, abs=2)
    assert api["ODOMETRY"] == 0 and gcs["ODOMETRY"] == 0
    # GET_MESSAGE_INTERVAL answers for the asking link: MESSAGE_INTERVAL after the ACK
    replies = _command(v, 510, 141, link=1)
    assert replies[0].fields["result"] == MavResult.ACCEPTED
    assert replies[1].name == "MESSAGE_INTERVAL" and replies[1].fields["interval_us"] == 500_000
    assert _command(v, 510, 141, link=0)[1].fields["interval_us"] == 100_000
    assert _command(v, 510, 331, link=0)[1].fields["interval_us"] == 0  # stopped
    # 0: back to the link's default
    _command(v, MavCmd.SET_MESSAGE_INTERVAL, 141, 0, link=1)
    assert _command(v, 510, 141, link=1)[1].fields["interval_us"] == 1_000_000
    # HEARTBEAT and messages the vehicle does not stream: FAILED (mavlink_receiver.cpp)
    assert _command(v, MavCmd.SET_MESSAGE_INTERVAL, 0, 100_000)[0].fields["result"] == MavResult.FAILED
    assert _command(v, MavCmd.SET_MESSAGE_INTERVAL, 9999, 100_000)[0].fields["result"] == MavResult.FAILED


def _last(v: Vehicle, name: str, seconds: float = 0.2) -> Msg:
    msgs = [m for m in v.advance(v.time_us + int(seconds * 1e6)) if m.name == name]
    assert msgs, name
    return msgs[-1]


def _fly_up(v: Vehicle) -> None:
    v.fly_until(lambda v: v.ready, 5_000_000)
    _command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    _command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, v.home_alt + 6)
    v.fly_until(lambda v: v.st.z < -5.5, 30_000_000)


def test_new_messages_hold_the_vehicles_state_on_the_ground():
    v = Vehicle(SimConfig(seed=2, wind=Wind(mean_speed=3, max_speed=3, direction=90)))
    v.fly_until(lambda v: v.ready, 5_000_000)
    imu = _last(v, "HIGHRES_IMU").fields
    assert imu["zacc"] == pytest.approx(-9.80665, abs=0.01)  # on the ground: -g in FRD
    assert abs(imu["xacc"]) < 0.01 and abs(imu["yacc"]) < 0.01
    assert imu["abs_pressure"] == pytest.approx(isa_pressure_hpa(v.home_alt), abs=0.01)
    assert 900 < imu["abs_pressure"] < 1013.25  # Zurich home at ~488 m AMSL
    assert math.hypot(imu["xmag"], imu["ymag"], imu["zmag"]) == pytest.approx(math.hypot(0.21, 0.01, 0.43))
    press = _last(v, "SCALED_PRESSURE", 1.0).fields
    assert press["press_abs"] == pytest.approx(imu["abs_pressure"], abs=0.01) and press["temperature"] == 2000
    wind = _last(v, "WIND_COV").fields
    assert wind["wind_x"] == pytest.approx(0.0, abs=1e-9) and wind["wind_y"] == pytest.approx(3.0)


def test_new_messages_hold_the_vehicles_state_in_flight():
    v = Vehicle(SimConfig(seed=3))
    _fly_up(v)
    wanted = {"ATTITUDE", "ATTITUDE_QUATERNION", "ALTITUDE", "ODOMETRY", "HIGHRES_IMU"}
    for _ in range(50):  # one 50 Hz tick that carries them all (ALTITUDE is 10 Hz)
        by = {m.name: m.fields for m in v.advance(v.time_us + 20_000)}
        if wanted <= by.keys():
            break
    st = v.st
    alt = by["ALTITUDE"]
    assert alt["altitude_local"] == pytest.approx(-st.z)
    assert alt["altitude_relative"] == pytest.approx(-(st.z - v.home[2]))  # ALTITUDE.hpp: home.z
    assert abs(v.home[2]) < 0.5
    assert alt["altitude_amsl"] == pytest.approx(v.home_alt - v.st.z, abs=1e-4)
    aq, att = by["ATTITUDE_QUATERNION"], by["ATTITUDE"]
    q = (aq["q1"], aq["q2"], aq["q3"], aq["q4"])
    assert math.fsum(c * c for c in q) == pytest.approx(1.0)
    w, x, y, z = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(2 * (w * y - z * x))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    assert (roll, pitch, yaw) == pytest.approx((att["roll"], att["pitch"], att["yaw"]), abs=1e-6)
    odom = by["ODOMETRY"]
    assert (odom["x"], odom["y"], odom["z"]) == pytest.approx((st.x, st.y, st.z))
    assert odom["frame_id"] == 1 and odom["child_frame_id"] == 1 and odom["estimator_type"] == 8
    assert list(odom["q"]) == pytest.approx(list(q))
    imu = by["HIGHRES_IMU"]
    assert imu["pressure_alt"] == pytest.approx(v.home_alt - v.body.z)
    assert imu["abs_pressure"] < isa_pressure_hpa(v.home_alt)  # higher: lower pressure
    assert math.hypot(imu["xacc"], imu["yacc"], imu["zacc"]) == pytest.approx(9.8, abs=1.5)  # hover ~ g


def test_system_time_is_the_host_clock_at_boot_plus_vehicle_time():
    boot = 1_763_900_000_000_000
    v = Vehicle(SimConfig(seed=1, utc_boot_us=boot))
    st = _last(v, "SYSTEM_TIME", 1.5).fields
    assert st["time_unix_usec"] == boot + st["time_boot_ms"] * 1000
    v0 = Vehicle(SimConfig(seed=1))  # in-process default: no clock, 1970, independent of the date
    assert _last(v0, "SYSTEM_TIME", 1.5).fields["time_unix_usec"] == 0


def test_autopilot_version_claims_only_what_is_served():
    caps = int(autopilot_version(Vehicle(SimConfig())).fields["capabilities"])
    served = 1 | 2 | 4 | 8 | 16 | 128 | 256 | 8192 | 16384 | 32768
    assert caps == served
    for absent in (32, 64, 512, 1024, 2048, 4096):  # FTP, SET_ATTITUDE_TARGET, TERRAIN, ...
        assert not caps & absent


def texts(msgs: list[Msg]) -> list[str]:
    """STATUSTEXT lines, MAVLink 2 chunks (same id, chunk_seq 0..) joined."""
    out: list[str] = []
    for m in msgs:
        if m.name != "STATUSTEXT":
            continue
        if m.fields["id"] and m.fields["chunk_seq"] > 0:
            out[-1] += m.fields["text"]
        else:
            out.append(m.fields["text"])
    return out


def _texts(v: Vehicle) -> list[str]:
    return texts(v.drain())


def test_an_unmodelled_command_is_unsupported_and_says_so():
    v = Vehicle(SimConfig())
    v.drain()
    ack = _command(v, 183, 1, 1500)[0]  # DO_SET_SERVO
    assert ack.fields["result"] == MavResult.UNSUPPORTED
    assert _texts(v) == ["MAV_CMD_DO_SET_SERVO not supported by the built-in simulator"]
    assert _command(v, 45_678)[0].fields["result"] == MavResult.UNSUPPORTED
    assert _texts(v) == ["MAV_CMD 45678 not supported by the built-in simulator"]
    # a modelled command that the vehicle refuses stays DENIED, with no 'not supported'
    v.fly_until(lambda v: v.ready, 5_000_000)
    _command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    _command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, v.home_alt + 6)
    v.fly_until(lambda v: v.st.z < -3, 20_000_000)
    v.drain()
    assert _command(v, MavCmd.COMPONENT_ARM_DISARM, 0)[0].fields["result"] == MavResult.DENIED
    assert not any("not supported" in t for t in _texts(v))


@pytest.mark.parametrize(
    ("main", "sub", "name"),
    [(4, 8, "AUTO_FOLLOW_TARGET"), (4, 9, "AUTO_PRECLAND"), (8, 0, "RATTITUDE")],
)
def test_a_mode_the_simulator_does_not_fly_is_unsupported(main: int, sub: int, name: str):
    v = Vehicle(SimConfig())
    v.fly_until(lambda v: v.ready, 5_000_000)
    v.drain()
    before = v.nav_state
    assert _command(v, MavCmd.DO_SET_MODE, 1, main, sub)[0].fields["result"] == MavResult.UNSUPPORTED
    assert _texts(v) == [f"Mode {name} not supported by the built-in simulator"]
    v.receive(Msg("SET_MODE", {"target_system": 1, "base_mode": 1, "custom_mode": main << 16 | sub << 24}))
    assert _texts(v) == [f"Mode {name} not supported by the built-in simulator"]
    assert v.nav_state == before
    # a flown mode is accepted
    assert _command(v, MavCmd.DO_SET_MODE, 1, 3, 0)[0].fields["result"] == MavResult.ACCEPTED
    assert not _texts(v)
