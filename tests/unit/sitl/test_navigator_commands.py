"""Navigator commands (DO_REPOSITION, DO_ORBIT, DO_LAND_START, DO_CHANGE_SPEED, CONDITION_YAW) and
mission changes in flight, in-process, as PX4 v1.15 does them (navigator_main.cpp, Commander.cpp,
FlightTaskOrbit.cpp, mission_base.cpp, mission_block.cpp)."""

from __future__ import annotations

import itertools
import math

import pytest

from uavtest.px4.modes import NavState
from uavtest.sitl.commander.vehicle_command import RESULT_CANCELLED
from uavtest.sitl.mav import MavCmd, MavFrame, MavResult, Msg
from uavtest.sitl.mission import NavItem, from_spec
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import Home, MissionItem, MissionItemKind

GCS = (255, 190)
HOME = Home()
INT32_MAX = 2**31 - 1


def command(v: Vehicle, cmd: int, *params: float) -> int:
    fields: dict[str, object] = {"command": cmd, "target_system": 1, "target_component": 1}
    fields.update({f"param{i}": p for i, p in enumerate(params, start=1)})
    (ack, *_) = v.receive(Msg("COMMAND_LONG", fields, *GCS))
    assert ack.name == "COMMAND_ACK" and ack.fields["command"] == cmd
    return int(ack.fields["result"])


def command_int(v: Vehicle, cmd: int, p: tuple[float, float, float, float], x: int, y: int, z: float) -> int:
    fields = {"command": cmd, "target_system": 1, "target_component": 1, "frame": 0, "x": x, "y": y, "z": z}
    fields.update({f"param{i}": q for i, q in enumerate(p, start=1)})
    (ack, *_) = v.receive(Msg("COMMAND_INT", fields, *GCS))
    return int(ack.fields["result"])


def texts(v: Vehicle, within_us: int = 0) -> list[str]:
    out = [m.fields["text"] for m in v.advance(v.time_us + within_us) if m.name == "STATUSTEXT"]
    return out


def hovering(alt: float = 10.0, **kw) -> Vehicle:
    v = Vehicle(SimConfig(home=HOME, **kw))
    v.fly_until(lambda v: v.ready, 5_000_000)
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME.alt + alt)
    v.fly_until(lambda v: v.nav_state == NavState.AUTO_LOITER and not v.landed, 40_000_000)
    v.fly_until(lambda v: False, 3_000_000)
    return v


def mission(with_land_start: bool = False, rtl: bool = False) -> list[NavItem]:
    items = [
        MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=8),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=HOME.lat + 0.0004, lon=HOME.lon, alt=8),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=HOME.lat + 0.0004, lon=HOME.lon + 0.0004, alt=8),
    ]
    if rtl:
        items.append(MissionItem(kind=MissionItemKind.RETURN))
    nav = from_spec(items)
    if with_land_start:
        nav.append(NavItem(len(nav), MavCmd.DO_LAND_START, MavFrame.MISSION))
        nav.append(
            NavItem(
                len(nav),
                MavCmd.NAV_LAND,
                MavFrame.GLOBAL_RELATIVE_ALT_INT,
                x=round((HOME.lat + 0.0001) * 1e7),
                y=round(HOME.lon * 1e7),
            )
        )
    return nav


# ---------------------------------------------------------------- ground-station bugs


def test_mission_upload_clear_and_set_current_while_holding_keep_holding():
    v = hovering()
    x, y, z = v.st.x, v.st.y, v.st.z
    v.load_mission(mission())
    v.receive(Msg("MISSION_SET_CURRENT", {"target_system": 1, "seq": 1}, *GCS))
    v.receive(Msg("MISSION_CLEAR_ALL", {"target_system": 1, "mission_type": 0}, *GCS))
    v.fly_until(lambda v: False, 10_000_000)
    assert v.nav_state == NavState.AUTO_LOITER and v.armed and not v.landed
    assert math.hypot(v.st.x - x, v.st.y - y) < 1.0 and abs(v.st.z - z) < 0.5


def test_mission_upload_during_return_keeps_returning():
    v = hovering()
    command(v, MavCmd.DO_REPOSITION, -1, 1, 0, math.nan, HOME.lat + 0.0003, HOME.lon, math.nan)
    v.fly_until(lambda v: v.st.x > 30, 30_000_000)
    assert command(v, MavCmd.NAV_RETURN_TO_LAUNCH) == MavResult.ACCEPTED
    v.fly_until(lambda v: False, 2_000_000)
    v.load_mission(mission())
    v.fly_until(lambda v: not v.armed, 120_000_000)
    # disarmed, PX4 is back in the last mode that may arm (UserModeIntention::onDisarm): Hold
    assert not v.armed and v.landed and v.nav_state == NavState.AUTO_LOITER
    assert math.hypot(v.st.x, v.st.y) < 2.0


def test_mission_rtl_item_switches_to_return_which_lands_and_disarms():
    v = Vehicle(SimConfig(home=HOME))
    v.load_mission(mission(rtl=True))
    v.fly_until(lambda v: v.ready, 5_000_000)
    assert command(v, MavCmd.MISSION_START) == MavResult.ACCEPTED
    v.fly_until(lambda v: v.nav_state == NavState.AUTO_RTL, 200_000_000)
    assert v.nav_state == NavState.AUTO_RTL and v.user_nav_state == NavState.AUTO_RTL and not v.landed
    v.fly_until(lambda v: not v.armed, 200_000_000)
    assert not v.armed and v.nav_state == NavState.AUTO_MISSION  # onDisarm: the mission again
    assert math.hypot(v.st.x, v.st.y) < 2.0


def test_set_current_in_mission_mode_jumps_and_clear_all_holds():
    v = Vehicle(SimConfig(home=HOME))
    v.load_mission(mission())
    v.fly_until(lambda v: v.ready, 5_000_000)
    command(v, MavCmd.MISSION_START)
    v.fly_until(lambda v: v.nav.current == 1 and -v.st.z > 7, 60_000_000)
    v.receive(Msg("MISSION_SET_CURRENT", {"target_system": 1, "seq": 2}, *GCS))
    assert v.nav.current == 2
    v.fly_until(lambda v: v.nav.reached == 2, 60_000_000)
    assert v.nav.reached == 2 and v.st.y > 25  # flew to item 2 (east), not item 1
    v.receive(Msg("MISSION_CLEAR_ALL", {"target_system": 1, "mission_type": 0}, *GCS))
    x, y = v.st.x, v.st.y
    v.fly_until(lambda v: False, 10_000_000)
    assert v.armed and not v.landed and math.hypot(v.st.x - x, v.st.y - y) < 2.0


# ---------------------------------------------------------------- DO_REPOSITION


def test_reposition_flies_to_the_point_in_hold_at_the_speed_and_yaw():
    v = hovering()
    lat, lon = HOME.lat + 0.0003, HOME.lon + 0.0002
    tx, ty = v.proj.project(lat, lon)
    r = command_int(
        v, MavCmd.DO_REPOSITION, (2.0, 1.0, 0.0, 1.0), round(lat * 1e7), round(lon * 1e7), HOME.alt + 15
    )
    assert r == MavResult.ACCEPTED and v.nav_state == NavState.AUTO_LOITER
    speeds = []
    for _ in range(200):
        v.advance(v.time_us + 100_000)
        speeds.append(math.hypot(v.body.vx, v.body.vy))
    assert max(speeds) < 2.6  # param1 ground speed, not MPC_XY_CRUISE (5)
    v.fly_until(lambda v: math.hypot(v.st.x - tx, v.st.y - ty) < 0.5, 60_000_000)
    v.fly_until(lambda v: False, 8_000_000)
    assert math.hypot(v.st.x - tx, v.st.y - ty) < 0.7 and abs(-v.st.z - 15) < 0.5
    assert abs(math.remainder(v.st.yaw - 1.0, 2 * math.pi)) < 0.1  # radians, as PX4 v1.15


def test_reposition_altitude_only_keeps_position():
    v = hovering()
    x, y = v.st.x, v.st.y
    assert (
        command_int(v, MavCmd.DO_REPOSITION, (-1, 1, 0, math.nan), INT32_MAX, INT32_MAX, HOME.alt + 14) == 0
    )
    v.fly_until(lambda v: False, 15_000_000)
    assert math.hypot(v.st.x - x, v.st.y - y) < 0.7 and abs(-v.st.z - 14) < 0.5


def test_reposition_without_change_mode_flag_is_unsupported_and_disarmed_only_switches_mode():
    v = hovering()
    assert (
        command(v, MavCmd.DO_REPOSITION, -1, 0, 0, math.nan, HOME.lat + 0.001, HOME.lon, math.nan)
        == MavResult.UNSUPPORTED
    )
    assert any("CHANGE_MODE" in t for t in texts(v))
    w = Vehicle(SimConfig(home=HOME))
    w.fly_until(lambda v: v.ready, 5_000_000)
    w.load_mission(mission())
    command(w, 176, 1, 4, 4)  # mission mode
    assert command(w, MavCmd.DO_REPOSITION, -1, 1, 0, math.nan, HOME.lat + 0.001, HOME.lon, math.nan) == 0
    assert w.nav_state == NavState.AUTO_LOITER and not w.armed
    w.fly_until(lambda v: False, 3_000_000)
    assert w.landed and math.hypot(w.body.x, w.body.y) < 0.1


# ---------------------------------------------------------------- DO_ORBIT


def test_orbit_circles_the_centre_at_the_radius_clockwise_facing_the_centre():
    v = hovering()
    lat, lon = HOME.lat + 0.0002, HOME.lon
    cx, cy = v.proj.project(lat, lon)
    r = command_int(
        v, MavCmd.DO_ORBIT, (8.0, 2.0, math.nan, 0.0), round(lat * 1e7), round(lon * 1e7), HOME.alt + 10
    )
    assert r == MavResult.ACCEPTED and v.nav_state == NavState.ORBIT
    v.fly_until(lambda v: not v.nav.orbit.approach, 60_000_000)
    v.fly_until(lambda v: False, 3_000_000)  # on the circle within 2 m (PX4), then settles
    angles = []
    status = []
    for _ in range(100):
        status += [m for m in v.advance(v.time_us + 200_000) if m.name == "ORBIT_EXECUTION_STATUS"]
        d = math.hypot(v.st.x - cx, v.st.y - cy)
        assert abs(d - 8.0) < 1.0
        facing = math.atan2(cy - v.st.y, cx - v.st.x)
        angles.append(math.atan2(v.st.y - cy, v.st.x - cx))
    assert abs(math.remainder(v.st.yaw - facing, 2 * math.pi)) < 0.35
    swept = sum(math.remainder(b - a, 2 * math.pi) for a, b in itertools.pairwise(angles))
    assert swept > 1.5  # clockwise (north → east), ~2 m/s over 20 s on r = 8: 5 rad ideally
    st = v.nav.orbit.status()
    assert st.radius == 8.0 and abs(st.x - cx) < 1e-6
    assert 35 <= len(status) <= 45  # 2 Hz over 20 s
    f = status[-1].fields
    assert (
        f["radius"] == 8.0
        and f["frame"] == 0
        and f["x"] == round(lat * 1e7)
        and abs(f["z"] - HOME.alt - 10) < 1e-3
    )


def test_orbit_negative_radius_is_counter_clockwise_and_too_large_radius_is_refused():
    v = hovering()
    command(v, MavCmd.DO_ORBIT, -6.0, 1.5, math.nan, 0, math.nan, math.nan, math.nan)
    assert v.nav.orbit.velocity < 0 and v.nav.orbit.status().radius == -6.0
    v.fly_until(lambda v: False, 30_000_000)
    assert command(v, MavCmd.DO_ORBIT, 5000.0, 1.0, math.nan, 0, math.nan, math.nan, math.nan) == 0
    assert "Orbit radius limit exceeded" in texts(v)
    assert v.nav_state == NavState.AUTO_LOITER


# ---------------------------------------------------------------- DO_LAND_START, speed, yaw


def test_land_start_jumps_to_the_landing_sequence_and_lands():
    v = Vehicle(SimConfig(home=HOME))
    v.load_mission(mission(with_land_start=True))
    v.fly_until(lambda v: v.ready, 5_000_000)
    command(v, MavCmd.MISSION_START)
    v.fly_until(lambda v: v.nav.current == 1 and -v.st.z > 7, 60_000_000)
    assert command(v, MavCmd.DO_LAND_START) == MavResult.ACCEPTED
    assert v.nav.current >= 3
    v.fly_until(lambda v: not v.armed, 120_000_000)
    lx, ly = v.proj.project(HOME.lat + 0.0001, HOME.lon)
    assert not v.armed and math.hypot(v.st.x - lx, v.st.y - ly) < 2.0
    assert v.nav.reached != 2  # item 2 (north-east) skipped


def test_land_start_without_one_is_cancelled():
    v = hovering()
    v.load_mission(mission())
    assert command(v, MavCmd.DO_LAND_START) == RESULT_CANCELLED
    assert "planned mission landing not available" in texts(v)
    assert v.nav_state == NavState.AUTO_LOITER


def test_change_speed_in_hold_and_reset():
    v = hovering()
    assert command(v, MavCmd.DO_CHANGE_SPEED, 1, 1.5, -1) == MavResult.ACCEPTED
    command(v, MavCmd.DO_REPOSITION, -1, 1, 0, math.nan, HOME.lat + 0.0004, HOME.lon, math.nan)
    top = 0.0
    for _ in range(150):
        v.advance(v.time_us + 100_000)
        top = max(top, math.hypot(v.body.vx, v.body.vy))
    assert top < 2.0
    assert command(v, MavCmd.DO_CHANGE_SPEED, 1, -1, -1) == MavResult.ACCEPTED
    assert math.isnan(v.nav.speed)


def test_condition_yaw_is_unsupported_as_in_px4():
    v = hovering()
    yaw = v.st.yaw
    assert command(v, MavCmd.CONDITION_YAW, 90, 20, 1, 0) == MavResult.UNSUPPORTED
    assert any("CONDITION_YAW" in t for t in texts(v, 3_000_000))
    assert abs(math.remainder(v.st.yaw - yaw, 2 * math.pi)) < 0.1


def test_takeoff_to_below_mis_takeoff_alt_climbs_only_there():
    """PX4 v1.15's Takeoff uses MIS_TAKEOFF_ALT (2.5 m) only when the command has no altitude: a
    takeoff to 1.5 m hovers at 1.5 m (the built-in vehicle used it as a minimum)."""
    v = hovering(alt=1.5)
    assert -v.body.z == pytest.approx(1.5, abs=0.4)


def test_a_new_mode_resets_the_cruise_speed_as_px4s_navigator_does():
    """reset_cruising_speed() on Loiter, Land, Takeoff, RtlDirect and Mission activation: a speed
    set by DO_CHANGE_SPEED in hold is not carried into Return."""
    v = hovering()
    assert command(v, MavCmd.DO_CHANGE_SPEED, 1, 1.5, -1) == MavResult.ACCEPTED
    assert v.nav.speed == 1.5
    assert command(v, MavCmd.NAV_RETURN_TO_LAUNCH) == MavResult.ACCEPTED
    v.advance(v.time_us + 200_000)
    assert v.nav_state == NavState.AUTO_RTL
    assert math.isnan(v.nav.speed)
