"""Geofence and rally points in-process, against PX4 v1.15 (navigator/geofence.cpp,
navigator_main.cpp geofence_breach_check, commander/failsafe, mavlink_mission.cpp, rtl.cpp)."""

from __future__ import annotations

import io
import math

from pyulog import ULog

from uavtest.px4.modes import AutoSubMode, MainMode, NavState
from uavtest.sitl.mav import MavCmd, MavFrame, MavResult, MissionResult, Msg
from uavtest.sitl.mission import NavItem
from uavtest.sitl.navigator.geofence import (
    NAV_FENCE_CIRCLE_EXCLUSION,
    NAV_FENCE_CIRCLE_INCLUSION,
    NAV_FENCE_POLYGON_VERTEX_INCLUSION,
    NAV_FENCE_RETURN_POINT,
    NAV_RALLY_POINT,
    rally_destination,
)
from uavtest.sitl.protocols import MissionProtocol
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig, Vehicle

GCS = (255, 190)
REL = MavFrame.GLOBAL_RELATIVE_ALT_INT
FENCE, RALLY = 1, 2


def command(v: Vehicle, cmd: int, *params: float) -> int:
    fields: dict[str, object] = {"command": cmd, "target_system": 1, "target_component": 1}
    fields.update({f"param{i}": p for i, p in enumerate(params, start=1)})
    (ack, *_) = v.receive(Msg("COMMAND_LONG", fields, *GCS))
    return int(ack.fields["result"])


def item(v: Vehicle | None, seq: int, cmd: int, x: float, y: float, p1: float = 0.0, mtype: int = FENCE,
         frame: int = REL, z: float = 0.0) -> Msg:  # fmt: skip
    if v is not None:
        lat, lon = v.proj.reproject(x, y)
    else:
        lat, lon = 47.397742 + x * 1e-5, 8.545594 + y * 1e-5
    return Msg(
        "MISSION_ITEM_INT",
        {"seq": seq, "command": cmd, "frame": frame, "param1": p1, "x": round(lat * 1e7),
         "y": round(lon * 1e7), "z": z, "autocontinue": 1, "mission_type": mtype},
        *GCS,
    )  # fmt: skip


def upload(target: Vehicle | MissionProtocol, items: list[Msg], mtype: int) -> list[Msg]:
    def send(m: Msg) -> list[Msg]:
        if isinstance(target, Vehicle):
            return target.receive(m)
        return target.handle(m, 0, 0) or []

    replies = send(Msg("MISSION_COUNT", {"count": len(items), "mission_type": mtype}, *GCS))
    for m in items:
        replies += send(m)
    return replies


def square(v: Vehicle | None, half: float, mtype_cmd: int = NAV_FENCE_POLYGON_VERTEX_INCLUSION) -> list[Msg]:
    corners = [(-half, -half), (half, -half), (half, half), (-half, half)]
    return [item(v, i, mtype_cmd, x, y, 4) for i, (x, y) in enumerate(corners)]


def texts_of(msgs: list[Msg]) -> list[str]:
    return [m.fields["text"] for m in msgs if m.name == "STATUSTEXT"]


def said(texts: list[str], text: str) -> int:
    """How often ``text`` was sent (a longer text goes as MAVLink 2 chunks: its first 50 characters)."""
    return texts.count(text[:50])


MAX_DIST = "Geofence violation: exceeding maximum distance to Home"
MAX_ALT = "Geofence violation: exceeding maximum altitude above Home"
OUTSIDE = "Geofence violation: approaching or outside geofence"


def ready(**params: float) -> Vehicle:
    v = Vehicle(SimConfig(params=params), MemorySink())
    v.fly_until(lambda v: v.ready, 5_000_000)
    return v


def take_off_then_sticks(v: Vehicle, until, within_s: float = 60.0, x: int = 600, y: int = 0) -> list[str]:
    """Arm, take off to 10 m, position mode, stick forward (North) until ``until(v)``; the texts."""
    out: list[str] = []
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, 488.0 + 10)
    v.fly_until(lambda v: v.nav_state == NavState.AUTO_LOITER and v.body.z < -9, 30_000_000)
    # PX4 switches to Position mode only with manual control: the sticks come first, centred
    v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}, *GCS))
    assert command(v, MavCmd.DO_SET_MODE, 1, MainMode.POSCTL, 0) == MavResult.ACCEPTED
    end = v.time_us + within_s * 1e6
    while v.time_us < end and not until(v):
        v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": x, "y": y, "z": 500, "r": 0}, *GCS))
        out += texts_of(v.advance(v.time_us + 100_000))
    return out


def fly(v: Vehicle, until, within_s: float) -> list[str]:
    """Keep the sticks centred (link alive) and fly on until ``until(v)``."""
    out: list[str] = []
    end = v.time_us + within_s * 1e6
    while v.time_us < end and not until(v):
        v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}, *GCS))
        out += texts_of(v.advance(v.time_us + 100_000))
    return out


# ------------------------------------------------------------------ protocol


def test_fence_upload_download_clear_apart_from_the_mission():
    proto = MissionProtocol()
    mission = [item(None, 0, MavCmd.NAV_WAYPOINT, 1, 0, mtype=0)]
    assert upload(proto, mission, 0)[-1].fields["type"] == MissionResult.ACCEPTED
    fence = [*square(None, 50), item(None, 4, NAV_FENCE_CIRCLE_EXCLUSION, 10, 10, 5),
             item(None, 5, NAV_FENCE_RETURN_POINT, 0, 0)]  # fmt: skip
    replies = upload(proto, fence, FENCE)
    assert [r.fields["mission_type"] for r in replies] == [FENCE] * 7
    assert [r.name for r in replies] == ["MISSION_REQUEST_INT"] * 6 + ["MISSION_ACK"]
    assert replies[-1].fields["type"] == MissionResult.ACCEPTED
    assert len(proto.fence) == 6 and len(proto.items) == 1 and proto.fence_installed is not None
    (count,) = proto.handle(Msg("MISSION_REQUEST_LIST", {"mission_type": FENCE}, *GCS), 0, 0) or []
    assert (count.fields["count"], count.fields["mission_type"]) == (6, FENCE)
    (circle,) = proto.handle(Msg("MISSION_REQUEST_INT", {"seq": 4, "mission_type": FENCE}, *GCS), 0, 0) or []
    assert circle.fields["command"] == NAV_FENCE_CIRCLE_EXCLUSION and circle.fields["param1"] == 5
    assert circle.fields["mission_type"] == FENCE
    (ack,) = proto.handle(Msg("MISSION_CLEAR_ALL", {"mission_type": FENCE}, *GCS), 0, 0) or []
    assert (ack.fields["type"], ack.fields["mission_type"]) == (MissionResult.ACCEPTED, FENCE)
    assert proto.fence == [] and len(proto.items) == 1  # the mission stays


def test_rally_plan_and_clear_all_types():
    proto = MissionProtocol()
    upload(proto, [item(None, 0, MavCmd.NAV_WAYPOINT, 1, 0, mtype=0)], 0)
    replies = upload(proto, [item(None, 0, NAV_RALLY_POINT, 30, 0, mtype=RALLY)], RALLY)
    assert (
        replies[-1].fields["type"] == MissionResult.ACCEPTED and replies[-1].fields["mission_type"] == RALLY
    )
    (count,) = proto.handle(Msg("MISSION_REQUEST_LIST", {"mission_type": RALLY}, *GCS), 0, 0) or []
    assert count.fields["count"] == 1
    (count,) = proto.handle(Msg("MISSION_REQUEST_LIST", {"mission_type": FENCE}, *GCS), 0, 0) or []
    assert count.fields["count"] == 0
    (ack,) = proto.handle(Msg("MISSION_CLEAR_ALL", {"mission_type": 255}, *GCS), 0, 0) or []
    assert ack.fields["type"] == MissionResult.ACCEPTED
    assert proto.items == [] and proto.rally == [] and proto.fence == []


def test_fence_refusals_as_px4():
    proto = MissionProtocol()
    two = [item(None, i, NAV_FENCE_POLYGON_VERTEX_INCLUSION, i, 0, 2) for i in range(2)]
    replies = upload(proto, two, FENCE)
    assert replies[1].fields["type"] == MissionResult.ERROR  # "Fence: too few vertices"
    local = [item(None, 0, NAV_FENCE_CIRCLE_INCLUSION, 0, 0, 50, frame=MavFrame.LOCAL_NED)]
    assert upload(proto, local, FENCE)[-1].fields["type"] == MissionResult.UNSUPPORTED_FRAME
    in_mission = [item(None, 0, NAV_FENCE_CIRCLE_INCLUSION, 0, 0, 50, mtype=0)]
    assert upload(proto, in_mission, 0)[-1].fields["type"] == MissionResult.ERROR
    assert upload(proto, [item(None, 0, 31000, 0, 0)], FENCE)[-1].fields["type"] == MissionResult.UNSUPPORTED
    assert proto.fence == [] and proto.items == []


# ------------------------------------------------------------------ breach and GF_ACTION


def test_max_hor_dist_return_holds_com_fail_act_t_then_returns_home():
    v = ready(GF_MAX_HOR_DIST=30, GF_ACTION=3)
    texts = take_off_then_sticks(v, lambda v: v.nav_state != NavState.POSCTL)
    assert said(texts, MAX_DIST) == 1
    assert "Failsafe activated: entering Hold for 5 seconds" in texts
    # the geofence checks the estimate (the vehicle truly is EKF2's error off it)
    assert v.nav_state == NavState.AUTO_LOITER and 30 <= v.st.x < 36
    t_hold = v.time_us
    texts = fly(v, lambda v: v.nav_state == NavState.AUTO_RTL, 10)
    assert v.nav_state == NavState.AUTO_RTL and 4.9e6 < v.time_us - t_hold < 5.3e6
    assert "Failsafe activated" in texts and v.user_nav_state == NavState.POSCTL
    fly(v, lambda v: not v.armed, 120)
    assert not v.armed and math.hypot(v.body.x, v.body.y) < 2.5


def test_polygon_hold_stops_at_the_fence():
    v = ready(GF_ACTION=2)
    replies = upload(v, square(v, 25), FENCE)
    assert replies[-1].fields["type"] == MissionResult.ACCEPTED
    texts = take_off_then_sticks(v, lambda v: v.nav_state != NavState.POSCTL)
    assert said(texts, OUTSIDE) == 1 and "Failsafe activated" in texts
    assert v.nav_state == NavState.AUTO_LOITER
    fly(v, lambda v: False, 10)
    assert v.nav_state == NavState.AUTO_LOITER and v.armed and 25 <= v.body.x < 31  # braked just outside


def test_exclusion_circle_land():
    v = ready(GF_ACTION=5, COM_FAIL_ACT_T=0)
    upload(v, [item(v, 0, NAV_FENCE_CIRCLE_EXCLUSION, 40, 0, 10)], FENCE)
    texts = take_off_then_sticks(v, lambda v: v.nav_state != NavState.POSCTL)
    assert said(texts, OUTSIDE) == 1
    assert v.nav_state == NavState.AUTO_LAND and 29 <= v.body.x < 36
    fly(v, lambda v: not v.armed, 60)
    assert not v.armed and 29 <= v.body.x < 37  # landed where it was, not home


def test_inclusion_circle_terminate_and_warning():
    v = ready(GF_ACTION=4)
    upload(v, [item(v, 0, NAV_FENCE_CIRCLE_INCLUSION, 0, 0, 20)], FENCE)
    take_off_then_sticks(v, lambda v: v.crashed)
    # the breach is judged on the estimate, which leads the truth (ekf2.py GPS_LEAD_S: ~0.3 m here)
    assert v.crashed and not v.body.motors and 19.5 <= v.body.x < 25
    v = ready(GF_ACTION=1)
    upload(v, [item(v, 0, NAV_FENCE_CIRCLE_INCLUSION, 0, 0, 20)], FENCE)
    texts = take_off_then_sticks(v, lambda v: v.body.x > 40)
    assert said(texts, OUTSIDE) == 1  # once per breach
    assert v.nav_state == NavState.POSCTL and v.body.x > 40  # a warning only


def test_no_action_no_check_and_max_ver_dist():
    v = ready(GF_MAX_HOR_DIST=20, GF_ACTION=0)
    texts = take_off_then_sticks(v, lambda v: v.body.x > 40)
    assert v.nav_state == NavState.POSCTL and not any("Geofence" in t for t in texts)
    v = ready(GF_MAX_VER_DIST=8, GF_ACTION=2)
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, 488.0 + 12)
    texts = fly(v, lambda v: v.body.z < -12, 30)
    # said on the breach, and again when the estimate, holding just below the limit, crosses it
    # (EKF2's altitude wanders by centimetres there, as PX4's does)
    assert said(texts, MAX_ALT) >= 1 and v.nav_state == NavState.AUTO_LOITER
    assert v.body.z > -12  # held: never climbed to the takeoff's 12 m


def test_fence_not_containing_home_is_dropped():
    v = ready(GF_ACTION=2)
    out = upload(v, [item(v, 0, NAV_FENCE_CIRCLE_INCLUSION, 100, 0, 20)], FENCE)
    assert out[-1].fields["type"] == MissionResult.ACCEPTED  # PX4 accepts the plan ...
    assert "Geofence invalid, doesn't contain Home position" in texts_of(v.drain())  # ... and drops the area
    assert v.nav.geofence.areas == []


def test_geofence_result_is_logged():
    v = ready(GF_MAX_HOR_DIST=30, GF_ACTION=3)
    take_off_then_sticks(v, lambda v: v.nav_state != NavState.POSCTL)
    fly(v, lambda v: not v.armed, 150)
    log = ULog(io.BytesIO(v.recorder.sink.logs[-1]))  # type: ignore[union-attr]
    gf = log.get_dataset("geofence_result").data
    assert set(gf["geofence_action"]) == {3}
    assert gf["geofence_max_dist_triggered"].any() and not gf["geofence_custom_fence_triggered"].any()
    dt = (gf["timestamp"][1:] - gf["timestamp"][:-1]).mean()
    assert abs(dt - 200_000) < 1_000  # GEOFENCE_CHECK_INTERVAL_US


def test_unfenced_flight_logs_no_geofence_result():
    v = ready()
    take_off_then_sticks(v, lambda v: v.body.x > 10)
    command(v, MavCmd.COMPONENT_ARM_DISARM, 0, 21196)
    v.advance(v.time_us + 100_000)
    log = ULog(io.BytesIO(v.recorder.sink.logs[-1]))  # type: ignore[union-attr]
    assert "geofence_result" not in {d.name for d in log.data_list}


# ------------------------------------------------------------------ mission feasibility


def _mission(v: Vehicle, north: float) -> list[NavItem]:
    lat, lon = v.proj.reproject(north, 0)
    return [
        NavItem(0, MavCmd.NAV_TAKEOFF, REL, z=10),
        NavItem(1, MavCmd.NAV_WAYPOINT, REL, x=round(lat * 1e7), y=round(lon * 1e7), z=10),
    ]


def test_mission_outside_the_fence_is_refused():
    v = ready(GF_MAX_HOR_DIST=50, GF_ACTION=3)
    v.load_mission(_mission(v, 100))
    assert "Geofence violation for waypoint 2" in texts_of(v.advance(v.time_us + 20_000))
    assert not v.nav.mission_valid
    # disarmed, PX4 takes the mode change and refuses to arm in it (no valid mission)
    assert command(v, MavCmd.DO_SET_MODE, 1, MainMode.AUTO, AutoSubMode.MISSION) == MavResult.ACCEPTED
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.TEMPORARILY_REJECTED
    v.load_mission(_mission(v, 40))
    assert v.nav.mission_valid
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED


# ------------------------------------------------------------------ rally points


def test_rtl_type_0_returns_to_the_closest_rally_point():
    v = ready()
    points = [(60, 0), (-60, 0), (5, 0)]  # the 5 m one is within 10 m of home: ignored
    upload(v, [item(v, i, NAV_RALLY_POINT, x, y, mtype=RALLY) for i, (x, y) in enumerate(points)], RALLY)
    take_off_then_sticks(v, lambda v: v.body.x > 35)
    fly(v, lambda v: False, 0.5)  # sticks centred first: moved in Return, they would take over
    assert command(v, MavCmd.NAV_RETURN_TO_LAUNCH) == MavResult.ACCEPTED
    fly(v, lambda v: not v.armed, 150)
    assert not v.armed and math.hypot(v.body.x - 60, v.body.y) < 2.5


def test_rtl_goes_home_when_home_is_closer_and_unmodelled_rtl_type_is_said():
    v = ready(RTL_TYPE=1)
    upload(v, [item(v, 0, NAV_RALLY_POINT, 60, 0, mtype=RALLY)], RALLY)
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED
    assert "RTL_TYPE 1 not modelled: Return flies RTL_TYPE 0" in texts_of(v.drain())
    command(v, MavCmd.COMPONENT_ARM_DISARM, 0, 21196)
    v.fly_until(lambda v: v.body.on_ground, 10_000_000)
    take_off_then_sticks(v, lambda v: v.body.x > 20)
    fly(v, lambda v: False, 0.5)  # sticks centred first (COM_RC_OVERRIDE)
    command(v, MavCmd.NAV_RETURN_TO_LAUNCH)
    fly(v, lambda v: not v.armed, 150)
    assert math.hypot(v.body.x, v.body.y) < 2.5  # home (20 m) is closer than the rally point (40 m)


def test_rally_destination_rules():
    home = (0.0, 0.0)
    assert rally_destination([(5.0, 0.0)], (50.0, 0.0), home) is None  # within 10 m of home: ignored
    assert rally_destination([(49.0, 0.0)], (50.0, 0.0), home) == (49.0, 0.0, 0)
    assert rally_destination([(30.0, 0.0)], (16.0, 0.0), home) is None  # 14 m + 2 m threshold vs 16 m


def test_geofence_allows_position_for_a_reposition():
    v = ready(GF_MAX_HOR_DIST=50, GF_ACTION=3)
    assert v.nav.geofence_allows_position(40, 0, 10) and not v.nav.geofence_allows_position(60, 0, 10)
    v.params.set("GF_ACTION", 1)  # warning only: PX4 lets a reposition through
    assert v.nav.geofence_allows_position(60, 0, 10)
