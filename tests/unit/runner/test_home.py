"""The vehicle's HOME_POSITION against the test's world.home: an error elsewhere, a warning higher."""

from __future__ import annotations

from uavtest.runner.core import Ending, ReplicaCore, Stage
from uavtest.runner.events import HomePosition, LocalPosition
from uavtest.runner.home import check_home
from uavtest.spec.models import Home

from .test_core import config
from .vehicle import ScriptedVehicle, boot, exchange

HOME = Home(lat=47.3977419, lon=8.5455938, alt=488.79)


def reported(lat: float, lon: float, alt: float) -> HomePosition:
    return HomePosition(round(lat * 1e7), round(lon * 1e7), round(alt * 1000))


def test_a_home_within_estimator_noise_is_the_tests_home() -> None:
    # what PX4 v1.15 SIH reported when started with PX4_HOME_LAT/LON and SIH_LOC_H0 = 488.786
    check = check_home(HOME, reported(47.39774301, 8.54559448, 489.01056))
    assert check.ok and check.horizontal_m < 0.5 and abs(check.vertical_m) < 0.5


def test_a_home_elsewhere_is_an_error_naming_both_positions() -> None:
    montreal = reported(45.4671160, -73.7578370, 32.34)  # PX4 v1.15 SIH's default place
    check = check_home(HOME, montreal)
    assert check.error is not None and check.warning is None
    assert "45.4671160, -73.7578370 at 32.3 m AMSL" in check.error
    assert "47.3977419, 8.5455938 at 488.8 m AMSL" in check.error
    assert "wrong place" in check.error and "km apart" in check.error


def test_a_few_metres_off_is_already_elsewhere() -> None:
    east_8m = reported(HOME.lat, HOME.lon + 8 / 75_300, HOME.alt)  # ~75.3 km per degree east here
    check = check_home(HOME, east_8m)
    assert check.error is not None and "m apart" in check.error and 7.5 < check.horizontal_m < 8.5


def test_the_right_place_at_another_altitude_is_a_warning() -> None:
    check = check_home(HOME, reported(HOME.lat, HOME.lon, 32.34))  # SIH_LOC_H0 left at its default
    assert check.error is None and check.warning is not None
    assert "world.home at 489 m" in check.warning and "32 m AMSL" in check.warning
    assert "(-456 m)" in check.warning
    assert round(check.vertical_m) == -456


def test_the_core_fails_before_the_flight_when_the_home_is_elsewhere() -> None:
    core = ReplicaCore(config(home=HOME))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, [reported(45.467116, -73.757837, 32.34)], wall=0.05)
    exchange(core, vehicle, boot(35_000), wall=0.1)
    assert core.done and core.report.ending is Ending.ERROR
    assert core.report.error is not None and core.report.error.startswith("home mismatch")
    assert core.report.start_ms is None  # nothing flew


def test_a_wrong_home_seen_in_the_flight_before_arming_ends_it_as_an_error() -> None:
    core = ReplicaCore(config(home=HOME))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, boot(35_000), wall=0.1)
    assert core.stage is Stage.FLIGHT
    exchange(core, vehicle, [reported(45.467116, -73.757837, 32.34)], wall=0.2)
    assert core.report.ending is Ending.ERROR and "home mismatch" in (core.report.error or "")


def test_an_altitude_mismatch_is_warned_once_and_the_flight_goes_on() -> None:
    core = ReplicaCore(config(home=HOME))
    vehicle = ScriptedVehicle()
    core.start(0.0)
    exchange(core, vehicle, boot(35_000), wall=0.1)
    for k in range(3):
        exchange(core, vehicle, [reported(HOME.lat, HOME.lon, 32.34 + k * 0.01)], wall=0.2 + k)
    exchange(core, vehicle, [LocalPosition(36_000, 0, 0, 0)], wall=4.0)
    assert core.stage is Stage.FLIGHT and core.report.error is None
    assert len(core.report.warnings) == 1 and "home altitude mismatch" in core.report.warnings[0]


def test_home_position_on_the_wire_becomes_an_event() -> None:
    from pymavlink.dialects.v20 import common as mavlink2

    from uavtest.runner.link import MavlinkCodec

    vehicle = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    msg = vehicle.home_position_encode(473977430, 85455945, 489011, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0)
    assert MavlinkCodec().decode(bytes(msg.pack(vehicle))) == [HomePosition(473977430, 85455945, 489011)]
