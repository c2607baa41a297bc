"""Collision Prevention as PX4 v1.15 (lib/collision_prevention) and the simulated range sensor
that feeds it: the scan against box geometry, the constraint's PX4 semantics (per-bin braking
limit, CP_DIST, CP_DELAY, CP_GUIDE_ANG, CP_GO_NO_DATA, stale data), and the vehicle flying
position mode at a wall with and without it."""

from __future__ import annotations

import math

import pytest

from uavtest.px4.modes import NavState
from uavtest.sitl.collision_prevention import (
    MAP_BINS,
    CollisionPrevention,
    CpParams,
    ObstacleMap,
    add_obstacle_distance,
    constrain_setpoint,
    max_speed_from_distance,
)
from uavtest.sitl.mav import Msg
from uavtest.sitl.sensor_obstacle_distance_sim import UINT16_MAX, ObstacleDistanceSim, scan
from uavtest.sitl.simulator_sih import World
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import Avoidance, BoxPosition, BoxSize, Obstacle, RangeSensor

SENSOR = RangeSensor()  # 360 degrees, 0.2-12 m, 10 Hz


def wall(x: float, w: float = 40.0, y: float = 0.0, r: float = 0.0) -> Obstacle:
    """A 2 m thick, 30 m tall wall whose near face is ``x`` metres North (for r 0)."""
    return Obstacle(size=BoxSize(l=2, w=w, h=30), position=BoxPosition(x=x + 1, y=y, z=0, r=r))


# --------------------------------------------------------------------------- the sensor


def test_scan_bins_see_the_boxes_where_geometry_puts_them() -> None:
    world = World([wall(5.0), Obstacle(size=BoxSize(l=2, w=2, h=30), position=BoxPosition(x=0, y=-8, z=0))])
    d = scan(world, 0.0, 0.0, -10.0, 0.0, SENSOR)
    assert len(d) == 72
    assert d[0] == 500  # straight ahead (bin 0 = front), cm
    # 30 degrees right: the same wall, further (the nearest of the bin's rays, 1/3 bin to the left)
    assert d[6] == round(500 / math.cos(math.radians(30 - 5 / 3)))
    assert d[54] == 700  # 270 degrees = left: the box 8 m West, its face at 7 m
    assert d[36] == 1201  # behind: nothing within 12 m: max_distance + 1
    # facing East, the wall North is on the left (270 degrees) and the box West behind
    east = scan(world, 0.0, 0.0, -10.0, math.pi / 2, SENSOR)
    assert east[54] == 500 and east[36] == 700 and east[0] == 1201


def test_the_scan_is_what_world_ray_sees_along_each_ray() -> None:
    """The scan casts only the rays that can reach a box; differential check against casting all
    216 rays with ``World.ray``, over random boxes, poses, fields of view and ranges."""
    import random

    def every_ray(world: World, x: float, y: float, z: float, yaw: float, s: RangeSensor) -> tuple[int, ...]:
        out = []
        for k in range(72):
            if not (s.fov >= 360 or min(k * 5, 360 - k * 5) <= s.fov / 2):
                out.append(UINT16_MAX)
                continue
            rays = [yaw + math.radians(k * 5 + d) for d in (-5 / 3, 0.0, 5 / 3)]
            near = min(world.ray(x, y, z, math.cos(a), math.sin(a), 0.0, s.max_range) for a in rays)
            out.append(round(s.max_range * 100) + 1 if near == math.inf else round(near * 100))
        return tuple(out)

    rng = random.Random(7)
    checked = 0
    for _ in range(150):
        boxes = [
            Obstacle(
                size=BoxSize(l=rng.uniform(0.5, 10), w=rng.uniform(0.5, 10), h=rng.uniform(1, 30)),
                position=BoxPosition(
                    x=rng.uniform(-20, 20),
                    y=rng.uniform(-20, 20),
                    z=rng.uniform(0, 5),
                    r=rng.uniform(-180, 180),
                ),
            )
            for _ in range(rng.randint(1, 6))
        ]
        world = World(boxes)
        sensor = RangeSensor(fov=rng.choice([360, 200, 90]), max_range=rng.choice([5, 12, 30]))
        x, y, z, yaw = rng.uniform(-15, 15), rng.uniform(-15, 15), -rng.uniform(0.5, 12), rng.uniform(-4, 4)
        if any(b.contains(x, y, z) for b in world.boxes):
            continue
        assert scan(world, x, y, z, yaw, sensor) == every_ray(world, x, y, z, yaw, sensor)
        checked += 1
    assert checked > 100


def test_field_of_view_and_range_limit_the_scan() -> None:
    world = World([wall(5.0)])
    narrow = scan(world, 0.0, 0.0, -10.0, 0.0, RangeSensor(fov=90, max_range=4))
    assert narrow[0] == 401  # the wall is beyond 4 m: in range, no obstacle
    assert [k for k, v in enumerate(narrow) if v != UINT16_MAX] == [*range(0, 10), *range(63, 72)]
    above = scan(world, 0.0, 0.0, -35.0, 0.0, SENSOR)  # above the 30 m wall: the scan plane is level
    assert above[0] == 1201


def test_the_sensor_publishes_at_its_rate() -> None:
    sim = ObstacleDistanceSim(RangeSensor(rate=5))
    world = World([wall(5.0)])
    stamps = [t for t in range(0, 2_000_000, 20_000) if sim.update(t, world, 0, 0, -10, 0) is not None]
    assert len(stamps) == 10 and stamps[1] - stamps[0] == 200_000
    od, ds = sim.last, sim.last_range
    assert od is not None and ds is not None
    assert (od.increment, od.frame, od.min_distance, od.max_distance) == (5.0, 12, 20, 1200)
    assert ds.current_distance == pytest.approx(5.0) and ds.orientation == 0


# --------------------------------------------------------------------------- the constraint


def _map(distances_by_map_bin: dict[int, int], t: int = 1_000_000, max_cm: int = 1200) -> ObstacleMap:
    """A map fed by one obstacle_distance whose 10-degree bins read as given (others: nothing)."""
    from uavtest.sitl.uorb import ObstacleDistance

    d = [max_cm + 1] * 72
    for i, v in distances_by_map_bin.items():
        d[2 * i] = v  # PX4 samples the 5-degree message at every other bin
    m = ObstacleMap(0)
    add_obstacle_distance(m, ObstacleDistance(t, 5.0, 0.0, tuple(d), 20, max_cm, 12, 0), 0.0, t)
    return m


P = CpParams(dist=2.0, delay=0.4, guide_ang=30.0, go_no_data=False, xy_p=0.95, jerk_max=8.0, acc_hor=3.0)


def test_speed_towards_an_obstacle_is_what_stops_cp_dist_short() -> None:
    p = CpParams(dist=2.0, guide_ang=0.0)  # no guidance: PX4 would steer around a lone post
    m = _map({0: 600})  # 6 m ahead
    vx, vy = constrain_setpoint(m, (10.0, 0.0), (0.0, 0.0), 0.0, 1_000_000, p)
    stop = 6.0 - 2.0
    assert vy == pytest.approx(0.0, abs=1e-9)
    assert vx == pytest.approx(min(0.95 * stop, max_speed_from_distance(8.0, 3.0, stop)))
    # CP_DELAY: 3 m/s towards it eats 1.2 m of the braking distance
    vx_moving, _ = constrain_setpoint(_map({0: 600}), (10.0, 0.0), (3.0, 0.0), 0.0, 1_000_000, p)
    assert vx_moving == pytest.approx(min(0.95 * (stop - 1.2), max_speed_from_distance(8.0, 3.0, stop - 1.2)))
    # at CP_DIST it stops; backing away is free
    assert constrain_setpoint(_map({0: 200}), (10.0, 0.0), (0.0, 0.0), 0.0, 1_000_000, p) == (0.0, 0.0)
    assert constrain_setpoint(_map({0: 200}), (-4.0, 0.0), (0.0, 0.0), 0.0, 1_000_000, p) == pytest.approx(
        (-4.0, 0.0)
    )


def test_a_lone_post_ahead_is_steered_around_within_cp_guide_ang() -> None:
    vx, vy = constrain_setpoint(_map({0: 600}), (10.0, 0.0), (0.0, 0.0), 0.0, 1_000_000, P)
    assert math.degrees(math.atan2(vy, vx)) == pytest.approx(-20.0)  # the lowest-cost bin, left


def test_sensor_range_limits_speed_in_the_open() -> None:
    """PX4: 'Collision prevention may restrict vehicle maximum speed if the sensor range isn't
    large enough': nothing within 12 m still means stop within 12 m."""
    vx, _ = constrain_setpoint(_map({}), (10.0, 0.0), (0.0, 0.0), 0.0, 1_000_000, P)
    assert vx == pytest.approx(max_speed_from_distance(8.0, 3.0, 12.01 - 2.0))
    assert vx < 10.0


def test_guidance_turns_the_setpoint_along_a_wall_by_at_most_cp_guide_ang() -> None:
    # a wall 4 m North: the distances its bins see (map bin i at i * 10 degrees)
    seen = {i: 400 / math.cos(math.radians(10 * i)) for i in range(-8, 9)}
    wall_bins = {i: round(cm) for i, cm in seen.items() if cm <= 1200}
    m = _map({i % MAP_BINS: v for i, v in wall_bins.items()})
    sp = (5 * math.cos(math.radians(35)), 5 * math.sin(math.radians(35)))  # 35 degrees right of North
    vx, vy = constrain_setpoint(m, sp, (0.0, 0.0), 0.0, 1_000_000, P)
    # the setpoint's bin is 30 degrees (3); the best within +-3 bins is 60 degrees: PX4 flies the
    # bin's direction, away from the wall
    assert math.degrees(math.atan2(vy, vx)) == pytest.approx(60.0, abs=1e-6)
    m0 = _map({i % MAP_BINS: v for i, v in wall_bins.items()})
    vx0, vy0 = constrain_setpoint(m0, sp, (0.0, 0.0), 0.0, 1_000_000, CpParams(dist=2.0, guide_ang=0.0))
    assert math.degrees(math.atan2(vy0, vx0)) == pytest.approx(35.0, abs=1e-6)  # CP_GUIDE_ANG 0: kept
    assert math.hypot(vx0, vy0) < math.hypot(vx, vy)  # straighter at the wall: slower


def test_no_data_in_the_setpoint_direction_stops_unless_cp_go_no_data() -> None:
    from uavtest.sitl.uorb import ObstacleDistance

    def front_only() -> ObstacleMap:  # a 90-degree sensor seeing nothing: data ahead only
        d = scan(World([]), 0, 0, -10, 0, RangeSensor(fov=90))
        m = ObstacleMap(0)
        add_obstacle_distance(m, ObstacleDistance(1_000_000, 5.0, 0.0, d, 20, 1200, 12, 0), 0.0, 1_000_000)
        return m

    back = (-3.0, 0.0)
    assert constrain_setpoint(front_only(), back, (0.0, 0.0), 0.0, 1_000_000, P) == (0.0, 0.0)
    go = CpParams(dist=2.0, go_no_data=True)
    assert constrain_setpoint(front_only(), back, (0.0, 0.0), 0.0, 1_000_000, go) == pytest.approx(back)
    # a bin that once had data and went stale stops the vehicle even with CP_GO_NO_DATA
    m = front_only()
    assert constrain_setpoint(m, (3.0, 0.0), (0.0, 0.0), 0.0, 1_000_000 + 400_000, go) != (0.0, 0.0)
    m.timestamp = 1_000_000 + 700_000  # newer data arrived for other bins only
    assert constrain_setpoint(m, (3.0, 0.0), (0.0, 0.0), 0.0, 1_000_000 + 700_000, go) == (0.0, 0.0)


def test_every_other_message_bin_is_used_as_in_px4() -> None:
    """PX4's map bin i reads message bin ceil(i * 10 / 5) = 2i: a post seen only at 5 degrees
    (message bin 1) is not in the map."""
    from uavtest.sitl.uorb import ObstacleDistance

    d = [1201] * 72
    d[1] = 300
    m = ObstacleMap(0)
    add_obstacle_distance(m, ObstacleDistance(10, 5.0, 0.0, tuple(d), 20, 1200, 12, 0), 0.0, 10)
    assert 300 not in m.distances and m.distances[0] == 1201


def test_stale_data_holds_still_then_switches_to_hold_after_5_s() -> None:
    cp = CollisionPrevention(CpParams(dist=2.0), 0)
    cp.max_speed = 10.0
    t = 0
    while t <= 6_000_000 and not cp.want_hold:
        cp.now_us = t
        assert cp(5.0, 0.0, 0.0, 0.0, 0.0) == (0.0, 0.0)  # no obstacle data at all: no movement
        t += 20_000
    assert cp.want_hold and 5_000_000 < t <= 6_100_000


# --------------------------------------------------------------------------- the vehicle


def _fly_at_wall(params: dict[str, float], *, sensor: bool = True, seconds: float = 25.0) -> Vehicle:
    v = Vehicle(
        SimConfig(
            obstacles=(wall(24.0),),
            params={"COM_RC_IN_MODE": 1, **params},
            avoidance=Avoidance.COLLISION_PREVENTION if sensor else Avoidance.NONE,
            range_sensor=SENSOR if sensor else None,
            seed=3,
        )
    )
    v.fly_until(lambda v: v.ready, 10_000_000)

    def cmd(c: int, *p: float) -> None:
        fields = {"command": c, "target_system": 1, "target_component": 1}
        fields.update({f"param{i}": x for i, x in enumerate(p, start=1)})
        v.receive(Msg("COMMAND_LONG", fields))

    cmd(400, 1)
    cmd(22, 0, 0, 0, math.nan, math.nan, math.nan, v.home_alt + 10)
    v.fly_until(lambda v: v.body.z < -9.5 and v.nav_state == NavState.AUTO_LOITER, 60_000_000)
    v.receive(Msg("MANUAL_CONTROL", {"x": 0, "y": 0, "z": 500, "r": 0, "buttons": 0, "target": 1}))
    cmd(176, 1, 3, 0)  # position mode (PX4 needs manual control for it: the sticks come first)
    end = v.time_us + int(seconds * 1e6)
    v.closest = math.inf  # type: ignore[attr-defined]
    while v.time_us < end and not v.crashed:
        v.receive(Msg("MANUAL_CONTROL", {"x": 1000, "y": 0, "z": 500, "r": 0, "buttons": 0, "target": 1}))
        v.advance(v.time_us + 20_000)
        v.closest = min(v.closest, 24.0 - v.body.x)  # type: ignore[attr-defined]
    return v


def test_full_stick_at_a_wall_stops_about_cp_dist_short() -> None:
    v = _fly_at_wall({"CP_DIST": 2.0, "MPC_POS_MODE": 0})
    assert not v.crashed and v.nav_state == NavState.POSCTL
    # PX4's braking lags CP's setpoint (the drag-wound velocity integrator, EKF2's velocity error):
    # closer than CP_DIST, then the position is locked where the vehicle stopped (_updateXYlock)
    assert 1.0 < v.closest < 2.0  # type: ignore[attr-defined]
    assert v.closest <= 24.0 - v.body.x < 2.3  # type: ignore[attr-defined]  # held, stick still pushed


def test_without_cp_the_same_flight_is_a_collision() -> None:
    assert _fly_at_wall({}).crashed  # CP_DIST -1 (PX4's default)
    # CP_DIST alone does nothing in PX4 v1.15's default position mode (MPC_POS_MODE 4)
    assert _fly_at_wall({"CP_DIST": 2.0}).crashed


def test_cp_without_a_sensor_holds_still_and_switches_to_hold() -> None:
    v = _fly_at_wall({"CP_DIST": 2.0, "MPC_POS_MODE": 0}, sensor=False, seconds=8.0)
    assert not v.crashed and v.body.x < 1.0 and v.nav_state == NavState.AUTO_LOITER


# --------------------------------------------------------------------------- streams and the log


def _position_mode_vehicle(params: dict[str, float], sensor: RangeSensor | None, sink=None) -> Vehicle:
    from uavtest.sitl.telemetry import NORMAL, ONBOARD

    v = Vehicle(
        SimConfig(
            obstacles=(wall(24.0),),
            params={"COM_RC_IN_MODE": 1, **params},
            range_sensor=sensor,
            links=(("api", ONBOARD), ("gcs", NORMAL)),
        ),
        sink,
    )
    v.fly_until(lambda v: v.ready, 10_000_000)
    for c, p in ((400, (1,)), (22, (0, 0, 0, math.nan, math.nan, math.nan, v.home_alt + 10))):
        fields = {"command": c, "target_system": 1, "target_component": 1}
        fields.update({f"param{i}": x for i, x in enumerate(p, start=1)})
        v.receive(Msg("COMMAND_LONG", fields))
    v.fly_until(lambda v: v.body.z < -9.5 and v.nav_state == NavState.AUTO_LOITER, 60_000_000)
    # PX4 switches to Position mode only with manual control: the sticks come first, centred
    v.receive(Msg("MANUAL_CONTROL", {"target": 1, "x": 0, "y": 0, "z": 500, "r": 0}))
    v.receive(Msg("COMMAND_LONG", {"command": 176, "param1": 1, "param2": 3, "target_system": 1}))
    return v


def _count(v: Vehicle, seconds: float) -> tuple[dict[str, list[Msg]], dict[str, list[Msg]]]:
    api: dict[str, list[Msg]] = {}
    gcs: dict[str, list[Msg]] = {}
    end = v.time_us + int(seconds * 1e6)
    while v.time_us < end:
        # 60 % forward: 3.25 m/s after PX4's deadzone and expo (MPC_HOLD_DZ, MPC_XY_MAN_EXPO)
        v.receive(Msg("MANUAL_CONTROL", {"x": 600, "y": 0, "z": 500, "r": 0, "buttons": 0, "target": 1}))
        v.advance(v.time_us + 20_000, drain=False)
        a, g = v.drain_links()
        for m in a:
            api.setdefault(m.name, []).append(m)
        for m in g:
            gcs.setdefault(m.name, []).append(m)
    return api, gcs


def test_streams_at_px4_rates_only_with_a_sensor_and_cp_running() -> None:
    v = _position_mode_vehicle({"CP_DIST": 2.0, "MPC_POS_MODE": 0}, SENSOR)
    api, gcs = _count(v, 10.0)
    # mavlink_main.cpp: ONBOARD 10 Hz each; NORMAL DISTANCE_SENSOR 0.5 Hz, OBSTACLE_DISTANCE 1 Hz
    assert len(api["OBSTACLE_DISTANCE"]) == pytest.approx(100, abs=2)
    assert len(api["DISTANCE_SENSOR"]) == pytest.approx(100, abs=2)
    assert len(gcs["OBSTACLE_DISTANCE"]) == pytest.approx(10, abs=1)
    assert len(gcs["DISTANCE_SENSOR"]) == pytest.approx(5, abs=1)
    od = api["OBSTACLE_DISTANCE"][-1].fields  # obstacle_distance_fused: CP's 10-degree map
    assert od["increment"] == 0 and od["increment_f"] == 10.0 and od["frame"] == 12
    assert len(od["distances"]) == 72 and set(od["distances"][36:]) == {UINT16_MAX}
    assert od["distances"][0] < 1200 and od["min_distance"] == 20 and od["max_distance"] == 1200
    ds = api["DISTANCE_SENSOR"][-1].fields
    assert ds["orientation"] == 0 and ds["max_distance"] == 1200
    # the same reading: DISTANCE_SENSOR truncates to cm (DISTANCE_SENSOR.hpp), CP's map rounds and
    # levels it by cos(pitch) (CollisionPrevention.cpp _addDistanceSensorData)
    gap = ds["current_distance"] - od["distances"][0]
    assert -1 <= gap <= 0.01 * ds["current_distance"] + 1
    # a sensor but CP off (MPC_POS_MODE 4): PX4 publishes no obstacle_distance_fused
    api, _ = _count(_position_mode_vehicle({"CP_DIST": 2.0}, SENSOR), 2.0)
    assert "OBSTACLE_DISTANCE" not in api and len(api["DISTANCE_SENSOR"]) == pytest.approx(20, abs=1)
    # no sensor: neither
    api, _ = _count(_position_mode_vehicle({}, None), 2.0)
    assert "OBSTACLE_DISTANCE" not in api and "DISTANCE_SENSOR" not in api


def test_the_ulog_has_the_scan_and_cp_topics_in_px4_format() -> None:
    import io

    from pyulog import ULog

    from uavtest.sitl.recorder import MemorySink

    sink = MemorySink()
    v = _position_mode_vehicle({"CP_DIST": 2.0, "MPC_POS_MODE": 0}, SENSOR, sink)
    _count(v, 10.0)
    log = ULog(io.BytesIO(sink.current or b""))
    od = log.get_dataset("obstacle_distance")
    assert od.data["increment"][0] == 5.0 and od.data["frame"][0] == 12
    assert [f"distances[{k}]" in od.data for k in (0, 71)] == [True, True]
    assert (
        od.data["distances[0]"][-1] < 1200 and od.data["distances[36]"][-1] == 1201
    )  # wall ahead, open behind
    fused = log.get_dataset("obstacle_distance_fused")
    assert fused.data["increment"][0] == 10.0 and set(fused.data["distances[40]"]) == {UINT16_MAX}
    cc = log.get_dataset("collision_constraints").data
    # 0.6 stick: (0.6 - 0.1) / 0.9 = 0.556, expo 0.4 * 0.556 + 0.6 * 0.556^3 = 0.3251, x 10 m/s
    assert cc["original_setpoint[0]"][-1] == pytest.approx(3.251, abs=0.02)  # its North part
    assert cc["adapted_setpoint[0]"][-1] <= cc["original_setpoint[0]"][-1]
    ds = log.get_dataset("distance_sensor").data
    assert 4 <= len(ds["timestamp"]) <= 6 + 60  # the logger takes it at 1 Hz (from boot)
    assert set(ds["orientation"]) == {0}


# --------------------------------------------------------------------------- what the user is told


def _spec(**vehicle: object):
    from uavtest.spec.models import UavTestSpec

    sticks = [{"at": 1, "action": "mode", "mode": "position"}]
    return UavTestSpec.model_validate({"vehicle": vehicle, "commands": sticks})


def test_warnings_say_when_cp_will_not_act() -> None:
    from uavtest.spec.collision_prevention import collision_prevention_warnings as warn

    assert warn(_spec()) == []
    assert warn(_spec(avoidance="collision-prevention", params={"CP_DIST": 2, "MPC_POS_MODE": 0})) == []
    (off,) = warn(_spec(avoidance="collision-prevention"))
    assert "CP_DIST is -1" in off and "vehicle.params.CP_DIST" in off
    (mode,) = warn(_spec(avoidance="collision-prevention", params={"CP_DIST": 2}))
    assert "MPC_POS_MODE is 4" in mode and "MPC_POS_MODE: 0" in mode
    (blind,) = warn(_spec(params={"CP_DIST": 2, "MPC_POS_MODE": 0}))
    assert "no range sensor" in blind and "Hold after 5 s" in blind
    (px4,) = warn(_spec(simulator="px4", avoidance="collision-prevention"))
    assert "no obstacle-distance sensor" in px4 and "the runner sends PX4 OBSTACLE_DISTANCE" in px4
    assert "at 10 Hz of vehicle time" in px4
    (px4_blind,) = warn(_spec(simulator="px4", params={"CP_DIST": 2, "MPC_POS_MODE": 0}))
    assert "no range sensor" in px4_blind and "Hold after 5 s" in px4_blind


def test_range_sensor_spec_checks_its_ranges() -> None:
    from pydantic import ValidationError

    with pytest.raises(ValidationError, match=r"minRange 5\.0 is not below maxRange 4\.0"):
        RangeSensor.model_validate({"minRange": 5, "maxRange": 4})
    with pytest.raises(ValidationError):
        RangeSensor.model_validate({"fov": 400})
    from uavtest.spec.collision_prevention import range_sensor_of

    assert range_sensor_of(_spec(avoidance="collision-prevention")) == RangeSensor()
    assert range_sensor_of(_spec()) is None
    assert range_sensor_of(_spec(rangeSensor={"fov": 90})) == RangeSensor(fov=90)


def test_a_companion_obstacle_distance_feeds_cp_as_in_px4() -> None:
    """mavlink_receiver.cpp: OBSTACLE_DISTANCE from a MAVLink client becomes obstacle_distance;
    with no simulated sensor, a companion's scan showing a wall 3 m ahead stops the vehicle."""
    v = _position_mode_vehicle({"CP_DIST": 2.0, "MPC_POS_MODE": 0}, None)
    start_x = v.body.x
    for _ in range(200):  # 4 s, the companion scanning at 25 Hz (every other tick)
        if v._tick % 10 == 0:
            d = [1201] * 72
            d[0] = d[1] = d[71] = round((start_x + 3.0 - v.body.x) * 100)
            v.receive(
                Msg(
                    "OBSTACLE_DISTANCE",
                    {
                        "distances": d,
                        "increment_f": 5.0,
                        "min_distance": 20,
                        "max_distance": 1200,
                        "frame": 12,
                    },
                )
            )
        v.receive(Msg("MANUAL_CONTROL", {"x": 1000, "y": 0, "z": 500, "r": 0, "buttons": 0, "target": 1}))
        v.advance(v.time_us + 20_000)
    assert v.nav_state == NavState.POSCTL
    assert 0.3 < v.body.x - start_x < 1.5  # moved towards the reported wall, stopped short of CP_DIST


def test_mpc_pos_mode_0_flies_the_stick_velocity_and_locks_below_mpc_hold_max_xy() -> None:
    """FlightTaskManualPosition: the velocity setpoint is the stick's at once (no ramp); a centred
    stick controls velocity only until slower than MPC_HOLD_MAX_XY, then locks the position."""
    from uavtest.sitl.mc_pos_control import Controller, Goal, GoalKind, Limits
    from uavtest.sitl.params import ParamStore

    ctrl = Controller(Limits.of(ParamStore()))
    ctrl.direct_velocity, ctrl.hold_max_xy = True, 0.8
    ctrl.update(0.02, Goal(GoalKind.VELOCITY, sticks=(0.5, 0.0, 0.5, 0.0)), 0, 0, -10, 0, 0, 0, 0.0)
    # half stick, through MPC_HOLD_DZ 0.1 and MPC_XY_MAN_EXPO 0.6 (Sticks::getPitchRollExpo):
    # (0.5 - 0.1) / 0.9 = 0.444, 0.4 * 0.444 + 0.6 * 0.444^3 = 0.2305, x MPC_VEL_MANUAL 10, in one tick
    assert ctrl.vx == pytest.approx(2.3045, abs=1e-4) and ctrl.vy == 0.0
    centred = Goal(GoalKind.VELOCITY, sticks=(0.0, 0.0, 0.5, 0.0))
    ctrl.update(0.02, centred, 3.0, 0, -10, 2.0, 0, 0, 0.0)  # still 2 m/s: not locked
    assert not ctrl.xy_locked and ctrl.px == 3.0
    ctrl.update(0.02, centred, 4.0, 0, -10, 0.5, 0, 0, 0.0)  # slower than 0.8 m/s: locked here
    ctrl.update(0.02, centred, 4.2, 0, -10, 0.3, 0, 0, 0.0)
    assert ctrl.xy_locked and ctrl.px == 4.0
