"""Return mode as PX4 v1.15 flies it for a multicopter (rtl.cpp, rtl_direct.cpp, mission_block.cpp):
the return altitude lowered near the destination by the RTL_CONE_ANG cone, the activation's
"RTL: start return at N m (M m above destination)", and the turn to home's heading for the descent
and the landing."""

from __future__ import annotations

import math
import re

import pytest

from uavtest.px4.modes import NavState
from uavtest.sitl.geo import Projection
from uavtest.sitl.mav import MavCmd, MavResult, Msg
from uavtest.sitl.mc_pos_control import GoalKind, wrap_pi
from uavtest.sitl.navigator import EventKind, Navigator, State
from uavtest.sitl.navigator.rtl import rtl_heading_accepted, rtl_return_altitude, rtl_start_text
from uavtest.sitl.params import ParamStore
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import Home

GCS = (255, 190)
HOME = Home()
HOME_YAW = math.radians(120.0)
#: PX4 v1.15 SIH: RTL_RETURN_ALT 30 (rc.mc_defaults), RTL_MIN_DIST 10, NAV_ACC_RAD 2
SIH = {"return_alt": 30.0, "min_dist": 10.0, "acc_rad": 2.0}


# ---------------------------------------------------------------- the return altitude (rtl.cpp)


@pytest.mark.parametrize(
    ("dist", "alt", "cone", "expected"),
    [
        (50.0, 10.0, 45, 30.0),  # beyond RTL_MIN_DIST: RTL_RETURN_ALT
        (10.0, 3.0, 45, 10.0),  # at RTL_MIN_DIST still in the cone: dist / tan(45)
        (10.5, 3.0, 45, 30.0),
        (8.0, 3.0, 45, 8.0),
        (8.0, 3.0, 25, 8.0 / math.tan(math.radians(25.0))),  # a narrower cone: higher
        (8.0, 3.0, 80, 4.0),  # a wide cone: at least 2 NAV_ACC_RAD outside the acceptance radius
        (8.0, 3.0, 90, 4.0),  # clamped to 89 degrees: the same floor
        (1.5, 0.5, 45, 3.0),  # within NAV_ACC_RAD: twice the distance
        (0.0, 0.5, 45, 0.5),  # never below the vehicle
        (8.0, 20.0, 45, 20.0),
        (1.5, 3.0, 0, 30.0),  # no cone: RTL_RETURN_ALT whatever the distance (RTL_MIN_DIST unused)
        (50.0, 40.0, 0, 40.0),
    ],
)
def test_return_altitude_cone(dist: float, alt: float, cone: int, expected: float) -> None:
    got = rtl_return_altitude(dist, 0.0, alt, cone_half_angle_deg=cone, **SIH)
    assert got == pytest.approx(expected)
    # the same above a destination 100 m up (a datum-free rule)
    assert rtl_return_altitude(dist, 100.0, 100.0 + alt, cone_half_angle_deg=cone, **SIH) == pytest.approx(
        100.0 + expected
    )


def test_start_text_is_px4s_float32_ceilf() -> None:
    assert rtl_start_text(518.0, 488.0) == "RTL: start return at 518 m (30 m above destination)"
    assert rtl_start_text(494.2, 488.0) == "RTL: start return at 495 m (7 m above destination)"
    # PX4 adds RTL_RETURN_ALT to home's float32 AMSL altitude: home at 488.4 m gives 518.40002 m,
    # 30.00003 m above it, which ceilf says as 31
    home = 488.4
    assert rtl_start_text(home + 30.0, home) == "RTL: start return at 519 m (31 m above destination)"


def test_heading_acceptance_of_an_rtl_item() -> None:
    yaw = math.radians(100.0)
    assert not rtl_heading_accepted(yaw, math.radians(80.0), 12.0, -1.0)
    assert rtl_heading_accepted(yaw, math.radians(89.0), 12.0, -1.0)  # within MIS_YAW_ERR
    assert rtl_heading_accepted(yaw, math.radians(-80.0), 12.0, 2.0)  # MIS_YAW_TMT set: at once
    assert rtl_heading_accepted(math.nan, 0.0, 12.0, -1.0)  # none to wait for
    assert rtl_heading_accepted(yaw, 0.0, 12.0, -1.0, yaw_acceptance=False)  # avoidance's NaN


# ---------------------------------------------------------------- the items (rtl_direct.cpp)


def _nav(**params: float) -> Navigator:
    nav = Navigator(ParamStore(params), Projection(HOME.lat, HOME.lon), HOME.alt)
    nav.home = (0.0, 0.0, 0.0, HOME_YAW)
    return nav


def _texts(nav: Navigator) -> list[str]:
    out = [str(e.value[1]) for e in nav.events if e.kind is EventKind.TEXT]  # type: ignore[index]
    nav.events.clear()
    return out


def test_far_return_faces_the_way_then_descends_and_lands_facing_home() -> None:
    nav = _nav()
    st = State(x=0.0, y=40.0, z=-10.0, yaw=math.radians(90.0), landed=False)
    nav.enter(NavState.AUTO_RTL, st, 0.0)
    assert _texts(nav) == ["RTL: start return at 518 m (30 m above destination)"]
    # CLIMBING: straight up where Return started, holding the heading it had
    g = nav.update(st, 0.0)
    assert (g.kind, g.x, g.y, g.z, g.yaw) == (GoalKind.POSITION, 0.0, 40.0, pytest.approx(-30.0), st.yaw)
    st.x, st.y = 3.0, 41.0  # drifted on: the climb's position stays
    assert (nav.update(st, 1.0).x, nav.update(st, 1.0).y) == (0.0, 40.0)
    # MOVE_TO_LOITER from beyond RTL_MIN_DIST: the heading left to MPC_YAW_MODE (facing home)
    st.z = -29.5
    g = nav.update(st, 10.0)
    assert (g.kind, g.x, g.y, g.z) == (GoalKind.POSITION, 0.0, 0.0, pytest.approx(-30.0))
    assert math.isnan(g.yaw)
    # LOITER_DOWN to RTL_DESCEND_ALT, turning to home's heading
    st.x, st.y, st.yaw = 0.5, 0.5, math.radians(-90.0)
    g = nav.update(st, 20.0)
    assert (g.kind, g.z, g.yaw) == (GoalKind.POSITION, pytest.approx(-10.0), HOME_YAW)
    st.z = -10.2
    assert nav.update(st, 30.0).yaw == HOME_YAW and nav.update(st, 30.0).kind is GoalKind.POSITION  # turning
    st.yaw = HOME_YAW - math.radians(11.0)  # within MIS_YAW_ERR 12: reached; LOITER_HOLD 0 s,
    g = nav.update(st, 31.0)  # MOVE_TO_LAND_HOVER reached, LAND facing home's heading
    assert (g.kind, g.x, g.y, g.yaw) == (GoalKind.LAND, 0.0, 0.0, HOME_YAW)
    assert _texts(nav) == ["RTL: land at destination"]
    st.landed = True
    assert nav.update(st, 50.0).kind is GoalKind.IDLE


def test_close_return_climbs_in_the_cone_and_already_faces_home_heading() -> None:
    nav = _nav()
    st = State(x=6.0, y=0.0, z=-3.0, yaw=0.0, landed=False)
    nav.enter(NavState.AUTO_RTL, st, 0.0)
    assert _texts(nav) == ["RTL: start return at 494 m (6 m above destination)"]
    assert nav.update(st, 0.0).z == pytest.approx(-6.0)  # 6 m / tan(45 deg)
    st.z = -5.5
    g = nav.update(st, 5.0)  # within RTL_MIN_DIST: the return leg already turns to home's heading
    assert (g.x, g.y, g.yaw) == (0.0, 0.0, HOME_YAW)
    st.x, st.z = 0.3, -6.0  # over home facing north: the item waits for its heading
    assert nav.update(st, 9.0).kind is GoalKind.POSITION
    st.yaw = HOME_YAW
    # RTL_DESCEND_ALT (10) is above the return altitude: the loiter is at the return altitude
    g = nav.update(st, 10.0)
    assert (g.kind, g.yaw) == (GoalKind.LAND, HOME_YAW)


def test_no_climb_when_higher_and_mis_yaw_tmt_accepts_the_heading_at_once() -> None:
    nav = _nav(MIS_YAW_TMT=2.0, RTL_CONE_ANG=0)
    st = State(x=0.0, y=5.0, z=-40.0, yaw=0.0, landed=False)
    nav.enter(NavState.AUTO_RTL, st, 0.0)
    assert _texts(nav) == ["RTL: start return at 528 m (40 m above destination)"]
    g = nav.update(st, 0.0)  # MOVE_TO_LOITER at once (getActivationLandState), home's heading
    assert (g.x, g.y, g.z, g.yaw) == (0.0, 0.0, pytest.approx(-40.0), HOME_YAW)
    st.y = 0.5
    g = nav.update(st, 1.0)  # over home facing North: no wait for home's heading
    assert (g.kind, g.z, g.yaw) == (GoalKind.POSITION, pytest.approx(-10.0), HOME_YAW)
    st.z = -10.0
    assert nav.update(st, 2.0).kind is GoalKind.LAND


def test_negative_land_delay_loiters_for_ever_holding_the_heading() -> None:
    nav = _nav(RTL_LAND_DELAY=-1.0)
    st = State(x=0.0, y=0.0, z=-10.0, yaw=HOME_YAW, landed=False)
    nav.enter(NavState.AUTO_RTL, st, 0.0)
    assert _texts(nav) == ["RTL: start return at 498 m (10 m above destination)"]  # no climb over home
    g = nav.update(st, 0.0)
    assert _texts(nav) == ["RTL: completed, loitering"]
    for t in (1.0, 100.0):
        g = nav.update(st, t)
        assert (g.kind, g.z) == (GoalKind.POSITION, pytest.approx(-10.0)) and math.isnan(g.yaw)
    assert _texts(nav) == []


def test_home_without_a_heading_takes_the_state_the_next_mode_starts_with() -> None:
    nav = Navigator(ParamStore(), Projection(HOME.lat, HOME.lon), HOME.alt)
    nav.home = (1.0, 2.0, -0.1)  # as the commander sets it on arming, before the mode starts
    assert nav.home == (1.0, 2.0, -0.1) and math.isnan(nav.home_yaw)
    nav.enter(NavState.AUTO_LOITER, State(x=1.0, y=2.0, z=-0.1, yaw=0.7), 0.0)
    assert nav.home_yaw == 0.7
    nav.enter(NavState.AUTO_LOITER, State(yaw=-1.0), 1.0)
    assert nav.home_yaw == 0.7


# ---------------------------------------------------------------- the built-in vehicle


def _command(v: Vehicle, cmd: int, *params: float) -> int:
    fields: dict[str, object] = {"command": cmd, "target_system": 1, "target_component": 1}
    fields.update({f"param{i}": p for i, p in enumerate(params, start=1)})
    (ack, *_) = v.receive(Msg("COMMAND_LONG", fields, *GCS))
    return int(ack.fields["result"])


def _statustexts(msgs: list[Msg]) -> list[str]:
    """STATUSTEXTs, a longer text's MAVLink 2 chunks joined."""
    out: list[str] = []
    for m in msgs:
        if m.name == "STATUSTEXT":
            if m.fields["chunk_seq"]:
                out[-1] += m.fields["text"]
            else:
                out.append(m.fields["text"])
    return out


def _hover_at(east: float, alt: float, **params: float) -> Vehicle:
    """Take off to ``alt`` over home, then stop ``east`` m East of it."""
    v = Vehicle(SimConfig(home=HOME, params=params))
    v.fly_until(lambda v: v.ready, 5_000_000)
    assert _command(v, MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED
    _command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME.alt + alt)
    v.fly_until(lambda v: v.nav_state == NavState.AUTO_LOITER and not v.landed, 40_000_000)
    lat, lon = Projection(HOME.lat, HOME.lon).reproject(0.0, east)
    _command(v, MavCmd.DO_REPOSITION, -1, 1, 0, math.nan, lat, lon, math.nan)
    v.fly_until(lambda v: abs(v.st.y - east) < 0.3 and math.hypot(v.body.vx, v.body.vy) < 0.1, 60_000_000)
    return v


def _return(v: Vehicle) -> tuple[list[str], list[tuple[float, float, float, bool]]]:
    """Return until disarmed: the texts and (east, altitude, heading, landed) every 20 ms."""
    assert _command(v, MavCmd.NAV_RETURN_TO_LAUNCH) == MavResult.ACCEPTED
    msgs: list[Msg] = []
    track = []
    while v.armed and v.time_us < 600_000_000:
        msgs += v.advance(v.time_us + 20_000)
        track.append((v.st.y, -v.st.z, v.st.yaw, v.landed))
    return _statustexts(msgs), track


@pytest.mark.parametrize(("cone", "rule"), [(45, "cone"), (25, "cone"), (0, "return_alt")])
def test_a_return_near_home_climbs_as_px4(cone: int, rule: str) -> None:
    """6 m from home at 3 m: PX4 v1.15 climbs to dist / tan(RTL_CONE_ANG) (the old rule: within
    RTL_MIN_DIST no climb); without a cone to RTL_RETURN_ALT."""
    v = _hover_at(6.0, 3.0, RTL_CONE_ANG=cone)
    hx, hy, _ = v.nav.home
    dist = math.hypot(v.st.x - hx, v.st.y - hy)
    above = dist / math.tan(math.radians(cone)) if rule == "cone" else 30.0
    home_amsl = v.commander.home[5]
    texts, track = _return(v)
    start = next(t for t in texts if t.startswith("RTL: start return"))
    m = re.fullmatch(r"RTL: start return at (\d+) m \((\d+) m above destination\)", start)
    assert m is not None, start
    assert int(m[1]) - home_amsl == pytest.approx(above, abs=1.0)
    if rule == "cone":  # not an integer: no float32 rounding at stake
        assert (int(m[1]), int(m[2])) == (math.ceil(home_amsl + above), math.ceil(above))
    assert above - 0.8 <= max(alt for _, alt, _, _ in track) <= above + 0.5
    assert texts[-3:] == ["RTL: land at destination", "Landing detected", "Disarmed by landing"]


def test_a_return_lands_facing_home_heading() -> None:
    """From 30 m East: the return leg faces home (MPC_YAW_MODE 0, West), the descent turns to the
    heading home was set with (armed facing North), the vehicle lands facing it."""
    v = _hover_at(30.0, 10.0)
    home_yaw = v.commander.home[6]
    # flew out facing East (the heading locks on the last approach, which EKF2's errors turn)
    assert abs(wrap_pi(v.st.yaw - math.radians(90.0))) < math.radians(15.0)
    texts, track = _return(v)
    # the last half of the leg (the first turns 180 degrees at MPC_YAWRAUTO_MAX, overshooting)
    on_the_way = [yaw for east, alt, yaw, _ in track if 3.0 < east < 15.0 and alt > 29.0]
    # (within 12 degrees: a few metres out, half a metre off the track turns the way home by 10)
    assert on_the_way and all(abs(wrap_pi(yaw + math.pi / 2)) < math.radians(12.0) for yaw in on_the_way)
    touchdown = next(yaw for _, _, yaw, landed in track if landed)
    assert abs(wrap_pi(touchdown - home_yaw)) < math.radians(5.0), math.degrees(touchdown)
    assert "RTL: land at destination" in texts
