"""Auto-disarm as PX4 v1.15's commander does it (Commander.cpp ``handleAutoDisarm``).

After a takeoff, the vehicle disarms once the land detector has said landed for COM_DISARM_LAND
seconds (2 s; <= 0: never), in every mode: until then the log, HEARTBEAT and vehicle_status say
armed, on the ground. In Mission mode the time starts when the mission is finished
(``landed_amid_mission``), i.e. when the navigator has seen the landing of its land item. Armed
without a takeoff, it disarms after COM_DISARM_PRFLT.
"""

from __future__ import annotations

import io
import math

from pyulog import ULog

from uavtest.px4.modes import NavState, nav_state_from_custom_mode, split_custom_mode
from uavtest.sitl.commander.arming import Reason
from uavtest.sitl.mav import MavCmd
from uavtest.sitl.mission import from_spec
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import Home, MissionItem, MissionItemKind

from .test_battery_failures import HOME_ALT, Flight

TICK_S = 0.02  # the commander's tick


class Logged(Flight):
    """A Flight whose ULog is kept, and whose HEARTBEATs are recorded (time, armed, nav state)."""

    def __init__(self, **params: float) -> None:
        super().__init__(**params)
        self.sink = MemorySink()
        self.v = Vehicle(SimConfig(params=params), self.sink)
        self.heartbeats: list[tuple[float, bool, NavState | None]] = []

    def _take(self, msgs) -> None:
        super()._take(msgs)
        for m in msgs:
            if m.name == "HEARTBEAT":
                ns = nav_state_from_custom_mode(*split_custom_mode(m.fields["custom_mode"]))
                self.heartbeats.append((self.v.time_us / 1e6, bool(m.fields["base_mode"] & 128), ns))

    def text_time(self, text: str) -> float:
        return next(t for t, said in self.texts if said == text)

    def ulog(self) -> ULog:
        self.v.recorder.stop()
        return ULog(io.BytesIO(self.sink.logs[-1]))


def _land_with(command: int, **params: float) -> Logged:
    f = Logged(**params)
    f.takeoff(5)
    assert f.command(command) == 0
    f.fly(90, until=lambda v: v.landed)
    assert f.v.landed and f.v.armed
    return f


def test_return_disarms_com_disarm_land_after_landing_armed_until_then_in_log_and_heartbeat():
    f = _land_with(MavCmd.NAV_RETURN_TO_LAUNCH)
    landed = f.v.landed_at_us / 1e6
    f.fly(10, until=lambda v: not v.armed)
    assert not f.v.armed and f.v.commander.disarming_reason == Reason.AUTO_DISARM_LAND
    disarmed = f.text_time("Disarmed by landing")
    assert abs(disarmed - landed - 2.0) <= TICK_S
    # HEARTBEAT: armed on the ground in Return until the disarm (the 1 Hz stream)
    on_ground = [(t, armed, ns) for t, armed, ns in f.heartbeats if landed < t < disarmed]
    assert on_ground and all(armed and ns == NavState.AUTO_RTL for _, armed, ns in on_ground)
    # the log: landed, still armed, then disarmed COM_DISARM_LAND later
    log = f.ulog()
    status = log.get_dataset("vehicle_status").data
    land = log.get_dataset("vehicle_land_detected").data
    t_land, t_status = land["timestamp"] / 1e6, status["timestamp"] / 1e6
    landed_log = t_land[(land["landed"] == 1) & (t_land > f.v.takeoff_us / 1e6)][0]
    disarmed_log = t_status[(status["arming_state"] == 1) & (t_status > landed_log)][0]  # DISARMED
    assert abs(landed_log - landed) <= TICK_S
    assert 2.0 - TICK_S <= disarmed_log - landed_log <= 2.0 + 2 * TICK_S
    between = (t_status >= landed_log) & (t_status < disarmed_log)
    assert between.any() and (status["arming_state"][between] == 2).all()  # ARMING_STATE_ARMED
    assert status["latest_disarming_reason"][-1] == Reason.AUTO_DISARM_LAND
    armed = log.get_dataset("actuator_armed").data
    t_armed = armed["timestamp"] / 1e6
    assert armed["armed"][(t_armed >= landed_log) & (t_armed < disarmed_log)].all()


def test_land_mode_waits_com_disarm_land_seconds():
    f = _land_with(MavCmd.NAV_LAND, COM_DISARM_LAND=4.5)
    landed = f.v.landed_at_us / 1e6
    f.fly(3)
    assert f.v.armed and f.v.nav_state == NavState.AUTO_LAND
    f.fly(10, until=lambda v: not v.armed)
    assert abs(f.text_time("Disarmed by landing") - landed - 4.5) <= TICK_S


def test_com_disarm_land_0_keeps_it_armed_on_the_ground():
    f = _land_with(MavCmd.NAV_LAND, COM_DISARM_LAND=0)
    f.fly(15)  # more than COM_DISARM_PRFLT: it has taken off, so that does not apply either
    assert f.v.armed and f.v.landed and not f.said("Disarmed")


def _land_mission(f: Logged) -> None:
    """Fly a takeoff, waypoint, land mission from Mission mode to the disarm."""
    f.fly(120, until=lambda v: v.landed and v.takeoff_us > 0)
    f.fly(10, until=lambda v: not v.armed)
    texts = [said for _, said in f.texts]
    assert texts[-3:] == ["Landing detected", "Mission finished, landed", "Disarmed by landing"]
    landed, finished = f.text_time("Landing detected"), f.text_time("Mission finished, landed")
    assert landed <= finished <= landed + TICK_S  # the navigator sees the landing at once
    assert f.v.nav_state == NavState.AUTO_MISSION  # landed: no switch to Hold
    assert f.v.commander.disarming_reason == Reason.AUTO_DISARM_LAND


def _mission() -> list:
    home = Home()
    return from_spec(
        [
            MissionItem(kind=MissionItemKind.TAKEOFF, lat=home.lat, lon=home.lon, alt=5),
            MissionItem(kind=MissionItemKind.WAYPOINT, lat=home.lat + 0.0001, lon=home.lon, alt=5),
            MissionItem(kind=MissionItemKind.LAND, lat=home.lat + 0.0001, lon=home.lon, alt=0),
        ]
    )


def test_mission_armed_on_the_ground_disarms_as_soon_as_it_has_landed():
    """PX4's special case: armed on the ground, the preflight branch asks the auto-disarm
    hysteresis for "disarm" from the arming on; in the air, Mission mode (``landed_amid_mission``)
    never updates it, so when the landed mission finishes, COM_DISARM_LAND has long passed: the
    disarm follows at the commander's next tick."""
    f = Logged()
    f.v.load_mission(_mission())
    f.fly(5, until=lambda v: v.ready)
    f.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    f.command(MavCmd.DO_SET_MODE, 1, 4, 4)
    _land_mission(f)
    finished = f.text_time("Mission finished, landed")
    assert 0 < f.text_time("Disarmed by landing") - finished <= TICK_S + 1e-9


def test_mission_started_in_the_air_disarms_com_disarm_land_after_it_finished():
    """Taken off in Takeoff mode, held, then Mission: the hysteresis saw "not landed" in Hold, so
    the time runs from the mission's end (the landing the navigator saw), COM_DISARM_LAND long."""
    f = Logged()
    f.v.load_mission(_mission())
    f.takeoff(5)
    f.command(MavCmd.DO_SET_MODE, 1, 4, 4)
    _land_mission(f)
    finished = f.text_time("Mission finished, landed")
    assert abs(f.text_time("Disarmed by landing") - finished - 2.0) <= TICK_S + 1e-9


def test_armed_without_takeoff_disarms_after_com_disarm_prflt():
    f = Flight(COM_DISARM_PRFLT=4)
    f.fly(5, until=lambda v: v.ready)
    f.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    armed = f.v.armed_at_us / 1e6
    f.fly(10, until=lambda v: not v.armed)
    assert f.v.commander.disarming_reason == Reason.AUTO_DISARM_PREFLIGHT
    disarmed = next(t for t, said in f.texts if said == "Disarmed by auto preflight disarming")
    assert abs(disarmed - armed - 4.0) <= TICK_S


def test_a_takeoff_within_com_disarm_prflt_keeps_it_armed():
    """Once taken off (land detector) COM_DISARM_PRFLT no longer applies."""
    f = Flight(COM_DISARM_PRFLT=3)
    f.fly(5, until=lambda v: v.ready)
    f.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    f.command(MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME_ALT + 5)
    f.fly(10)
    assert f.v.armed and not f.v.landed
