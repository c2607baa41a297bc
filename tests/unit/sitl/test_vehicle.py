"""Commander, navigator and physics behaviour a client relies on, in-process."""

import math

from uavtest.px4.modes import AutoSubMode, MainMode, NavState
from uavtest.sitl.mav import LandedState, MavCmd, MavResult, Msg
from uavtest.sitl.mission import from_spec
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import BoxPosition, BoxSize, Home, MissionItem, MissionItemKind, Obstacle, Wind

GCS = (255, 190)


def command(v: Vehicle, cmd: int, *params: float, name: str = "COMMAND_LONG") -> int:
    fields: dict[str, object] = {"command": cmd, "target_system": 1, "target_component": 1}
    fields.update({f"param{i}": p for i, p in enumerate(params, start=1)})
    (ack, *_) = v.receive(Msg(name, fields, *GCS))
    assert ack.name == "COMMAND_ACK" and ack.fields["command"] == cmd
    return int(ack.fields["result"])


def ready_vehicle(**kw) -> Vehicle:
    v = Vehicle(SimConfig(**kw))
    v.fly_until(lambda v: v.ready, 5_000_000)
    return v


def test_arming_is_refused_until_ready_then_accepted():
    v = Vehicle(SimConfig())
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.TEMPORARILY_REJECTED
    v.fly_until(lambda v: v.ready, 5_000_000)
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 1) == MavResult.ACCEPTED
    assert v.armed


def test_unsupported_commands_get_unsupported():
    v = ready_vehicle()
    assert command(v, 31010) == MavResult.UNSUPPORTED
    assert command(v, 183, 1, 1500) == MavResult.UNSUPPORTED  # DO_SET_SERVO


def test_takeoff_climbs_to_mis_takeoff_alt_then_holds():
    v = ready_vehicle()
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    assert (
        command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, math.nan) == MavResult.ACCEPTED
    )
    v.fly_until(lambda v: v.nav_state == NavState.AUTO_LOITER and not v.landed, 30_000_000)
    v.advance(v.time_us + 5_000_000)
    assert abs(-v.st.z - 2.5) < 0.5  # MIS_TAKEOFF_ALT default: the estimate, which PX4 flies
    assert v.landed_state() == LandedState.IN_AIR


def test_disarm_in_air_is_denied_unless_forced_then_it_falls():
    v = ready_vehicle()
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, 488.0 + 5)
    v.fly_until(lambda v: -v.body.z > 4.0, 30_000_000)
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 0) == MavResult.DENIED
    assert command(v, MavCmd.COMPONENT_ARM_DISARM, 0, 21196) == MavResult.ACCEPTED
    assert not v.armed
    v.fly_until(lambda v: v.body.on_ground, 10_000_000)
    assert v.body.on_ground and v.landed


def test_land_command_lands_and_disarms():
    v = ready_vehicle()
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, 488.0 + 5)
    v.fly_until(lambda v: -v.body.z > 4.5, 30_000_000)
    assert command(v, MavCmd.NAV_LAND) == MavResult.ACCEPTED
    v.fly_until(lambda v: not v.armed, 60_000_000)
    assert not v.armed and v.landed and v.body.on_ground


def test_rtl_flies_home_and_lands():
    home = Home()
    items = [
        MissionItem(kind=MissionItemKind.TAKEOFF, lat=home.lat, lon=home.lon, alt=5),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=home.lat + 0.0003, lon=home.lon, alt=5),  # ~33 m north
        MissionItem(kind=MissionItemKind.LOITER_TIME, lat=home.lat + 0.0003, lon=home.lon, alt=5, hold=100),
    ]
    v = ready_vehicle(home=home)
    v.load_mission(from_spec(items))
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.DO_SET_MODE, 1, MainMode.AUTO, AutoSubMode.MISSION)
    v.fly_until(lambda v: v.body.x > 30, 60_000_000)
    assert command(v, MavCmd.NAV_RETURN_TO_LAUNCH) == MavResult.ACCEPTED
    v.fly_until(lambda v: -v.body.z > 25, 60_000_000)  # climbs to RTL_RETURN_ALT (30 m)
    v.fly_until(lambda v: not v.armed, 200_000_000)
    assert not v.armed
    assert math.hypot(v.body.x, v.body.y) < 2.5  # NAV_ACC_RAD 2


def test_position_mode_sticks_fly_forward():
    v = ready_vehicle()
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, 488.0 + 5)
    v.fly_until(lambda v: v.nav_state == NavState.AUTO_LOITER, 30_000_000)
    v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}, *GCS))  # needed
    assert command(v, MavCmd.DO_SET_MODE, 1, MainMode.POSCTL, 0) == MavResult.ACCEPTED
    x0 = v.body.x
    for _ in range(50):  # 5 s of full forward stick at 10 Hz (heading north)
        v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 1000, "y": 0, "z": 500, "r": 0}, *GCS))
        v.advance(v.time_us + 100_000)
    assert v.body.x - x0 > 15
    assert abs(-v.body.z - 5) < 1.5


def test_collision_with_a_box_is_a_crash():
    box = Obstacle(size=BoxSize(l=4, w=20, h=30), position=BoxPosition(x=20, y=0, z=0, r=0))
    home = Home()
    items = [
        MissionItem(kind=MissionItemKind.TAKEOFF, lat=home.lat, lon=home.lon, alt=10),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=home.lat + 0.0004, lon=home.lon, alt=10),  # 44 m north
    ]
    v = ready_vehicle(home=home, obstacles=(box,))
    v.load_mission(from_spec(items))
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.DO_SET_MODE, 1, MainMode.AUTO, AutoSubMode.MISSION)
    texts: list[str] = []
    while v.time_us < 80_000_000 and v.armed:
        texts += [m.fields["text"] for m in v.advance(v.time_us + 100_000) if m.name == "STATUSTEXT"]
    assert "crash: collided with obstacle 0" in texts
    assert v.crashed and not v.armed and v.body.on_ground
    assert 17.5 < v.body.x < 18.5  # stopped at the box's face (x = 18), then fell


def test_datalink_loss_failsafe_returns_when_configured():
    v = ready_vehicle(params={"NAV_DLL_ACT": 2, "COM_DL_LOSS_T": 5})
    v.receive(Msg("HEARTBEAT", {"type": 6, "autopilot": 8}, *GCS))
    command(v, MavCmd.COMPONENT_ARM_DISARM, 1)
    command(v, MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, 488.0 + 5)
    v.fly_until(lambda v: v.nav_state == NavState.AUTO_RTL, 30_000_000)
    assert v.nav_state == NavState.AUTO_RTL and v.gcs_lost


def test_wind_gusts_stay_below_max_speed():
    v = ready_vehicle(wind=Wind(mean_speed=3, max_speed=6, direction=90))
    speeds = []
    for _ in range(500):
        v.advance(v.time_us + 100_000)
        speeds.append(math.hypot(v.wind.n, v.wind.e))
    assert max(speeds) <= 6.0 + 1e-9
    assert max(speeds) > 3.5 and min(speeds) < 2.9  # it gusts
