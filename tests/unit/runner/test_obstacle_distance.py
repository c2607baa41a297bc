"""The range sensor the runner simulates for PX4 SITL: OBSTACLE_DISTANCE from the test's boxes."""

from __future__ import annotations

import itertools
import math

from uavtest.runner.core import CoreConfig, ReplicaCore, Stage
from uavtest.runner.events import Attitude, CommandLong, LocalPosition, ObstacleDistance, Outgoing
from uavtest.runner.obstacle_distance import ObstacleDistanceFeed
from uavtest.runner.plan import plan_flight
from uavtest.runner.streams import ATTITUDE_INTERVAL_US
from uavtest.spec.models import Obstacle, RangeSensor, UavTestSpec

from .vehicle import ScriptedVehicle, boot, exchange

#: a wall 2 m thick across the way North, its face at x = 10 m, 20 m wide, 30 m high
WALL = Obstacle.model_validate({"size": {"l": 2, "w": 20, "h": 30}, "position": {"x": 11, "y": 0, "z": 0}})


def _feed(**sensor: float) -> ObstacleDistanceFeed:
    return ObstacleDistanceFeed(RangeSensor(**sensor), [WALL])


def test_no_scan_until_the_heading_is_known() -> None:
    feed = _feed()
    assert feed.on_position(1000, 0.0, 0.0, -5.0) is None
    feed.on_attitude(0.0)
    assert isinstance(feed.on_position(1020, 0.0, 0.0, -5.0), ObstacleDistance)


def test_scans_come_at_the_sensors_rate_of_vehicle_time() -> None:
    feed = _feed(rate=10.0)
    feed.on_attitude(0.0)
    sent = [t for t in range(0, 2000, 33) if feed.on_position(t, 0.0, 0.0, -5.0) is not None]
    assert len(sent) == 20  # 10 Hz over 2 s, at the first position after each 100 ms
    assert all(99 <= b - a <= 133 for a, b in itertools.pairwise(sent))  # no drift


def test_the_scan_sees_the_wall_in_the_body_frame_as_px4_reads_it() -> None:
    feed = _feed()
    feed.on_attitude(0.0)  # facing North, at the wall
    scan = feed.on_position(0, 4.0, 0.0, -5.0)
    assert scan is not None
    assert scan.distances[0] == 600  # 6 m ahead, in cm
    assert scan.distances[36] == 1201  # behind: nothing within 12 m (max + 1)
    assert (scan.increment, scan.angle_offset, scan.frame, scan.min_cm, scan.max_cm) == (
        5.0,
        0.0,
        12,
        20,
        1200,
    )
    assert len(scan.distances) == 72
    turned = _feed()
    turned.on_attitude(math.radians(90.0))  # facing East: the wall is on the left, bin 270 degrees
    left = turned.on_position(0, 4.0, 0.0, -5.0)
    assert left is not None and left.distances[54] == 600 and left.distances[0] == 1201


def test_a_narrow_field_of_view_reports_no_data_outside_it() -> None:
    feed = _feed(fov=90.0)
    feed.on_attitude(0.0)
    scan = feed.on_position(0, 4.0, 0.0, -5.0)
    assert scan is not None and scan.distances[0] == 600
    assert scan.distances[18] == 65535 and scan.distances[36] == 65535  # UINT16_MAX: no data


def test_a_clock_that_went_back_restarts_the_scans() -> None:
    feed = _feed()
    feed.on_attitude(0.0)
    assert feed.on_position(60_000, 0.0, 0.0, -5.0) is not None
    assert feed.on_position(500, 0.0, 0.0, -5.0) is not None  # rebooted: scanning again at once


def test_px4_tests_with_a_range_sensor_get_the_runners_scans_and_the_builtin_its_own() -> None:
    doc = {
        "vehicle": {"avoidance": "collision-prevention"},
        "world": {"obstacles": [WALL.model_dump()]},
        "commands": [{"at": 1, "action": "arm"}],
    }
    px4 = UavTestSpec.model_validate({**doc, "vehicle": {**doc["vehicle"], "simulator": "px4"}})
    assert plan_flight(px4, endpoint="udpin:127.0.0.1:1").range_sensor == RangeSensor()
    assert plan_flight(UavTestSpec.model_validate(doc), endpoint="udpin:127.0.0.1:1").range_sensor is None
    plain = UavTestSpec.model_validate({"vehicle": {"simulator": "px4"}, "commands": doc["commands"]})
    assert plan_flight(plain, endpoint="udpin:127.0.0.1:1").range_sensor is None


def _connected(config: CoreConfig) -> tuple[ReplicaCore, list[Outgoing]]:
    """Connected, each message read on its own (a runner that keeps up)."""
    core = ReplicaCore(config)
    core.start(0.0)
    core.handle(Attitude(900, 0.0), 0.1)
    out: list[Outgoing] = []
    for msg in boot(1000):
        out += core.handle(msg, 0.1) + core.end_batch(0.1)
    out += core.handle(LocalPosition(1200, 4.0, 0.0, -5.0), 0.2) + core.end_batch(0.2)
    return core, out


def test_the_core_keeps_attitude_and_sends_scans_from_the_first_position() -> None:
    _, out = _connected(CoreConfig(obstacles=[WALL], range_sensor=RangeSensor()))
    scans = [m for m in out if isinstance(m, ObstacleDistance)]
    assert [s.time_usec for s in scans] == [1_000_000, 1_200_000]  # 10 Hz: both due
    assert scans[-1].distances[0] == 600
    asks = {int(m.params[0]): m.params[1] for m in out if isinstance(m, CommandLong) and m.command == 511}
    assert asks[30] == ATTITUDE_INTERVAL_US  # ATTITUDE kept for the heading
    _, out = _connected(CoreConfig(obstacles=[WALL]))
    assert not any(isinstance(m, ObstacleDistance) for m in out)
    asks = {int(m.params[0]): m.params[1] for m in out if isinstance(m, CommandLong) and m.command == 511}
    assert asks[30] == -1.0  # without a sensor to simulate: stopped, as before


def test_a_backlog_read_at_once_gets_one_scan_from_its_newest_position_and_a_warning() -> None:
    """PX4 at a high speed factor on a busy machine: the runner reads 2 s of positions at once.
    Scanning each would hand PX4 scans from where the vehicle was (PX4 stamps them new); one
    scan from the newest position, and the backlog said in the result."""
    core = ReplicaCore(CoreConfig(obstacles=[WALL], range_sensor=RangeSensor(), commands=[]))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    core.handle(Attitude(900, 0.0), 0.1)
    exchange(core, vehicle, boot(35_000), wall=0.1)
    assert core.stage is Stage.FLIGHT
    core.end_batch(0.1)  # what queued while connecting is not a backlog of the flight
    assert core.report.scan_backlog_ms == 0
    out: list[Outgoing] = []
    for k in range(1, 41):  # 0 -> 7.8 m North toward the wall's face at 10 m, 50 ms apart
        out += core.handle(LocalPosition(35_000 + 50 * k, 0.2 * (k - 1), 0.0, -5.0), 1.0)
    scans = [m for m in [*out, *core.end_batch(1.0)] if isinstance(m, ObstacleDistance)]
    assert [s.time_usec for s in scans] == [37_000_000]  # one, from the newest position
    assert scans[0].distances[0] == 220  # 10 - 7.8 m ahead, not 10 m from where it started
    assert core.report.scan_backlog_ms == 1950
    core.handle(LocalPosition(37_050, 7.8, 0.0, -5.0), 1.1)
    core.end_batch(1.1)  # read on its own: no backlog, the worst one kept
    assert core.report.scan_backlog_ms == 1950
    core._snapshot()  # what the flight's end does
    [warning] = [w for w in core.report.warnings if w.startswith("the runner fell")]
    assert "up to 1.9 s of vehicle time behind" in warning and "vehicle.speedFactor" in warning


def test_a_runner_that_keeps_up_scans_at_the_sensors_rate_and_warns_of_nothing() -> None:
    core = ReplicaCore(CoreConfig(obstacles=[WALL], range_sensor=RangeSensor(), commands=[]))
    core.start(0.0)
    core.handle(Attitude(900, 0.0), 0.1)
    exchange(core, ScriptedVehicle(), boot(35_000), wall=0.1)
    core.end_batch(0.1)
    scans = []
    for k in range(1, 41):  # each position read on its own, 50 ms apart
        core.handle(LocalPosition(35_000 + 50 * k, 0.1 * k, 0.0, -5.0), 1.0 + k / 1000)
        scans += [m for m in core.end_batch(1.0 + k / 1000) if isinstance(m, ObstacleDistance)]
    assert 19 <= len(scans) <= 21  # 10 Hz over 2 s
    core._snapshot()
    assert core.report.scan_backlog_ms == 0
    assert not any(w.startswith("the runner fell") for w in core.report.warnings)
