"""The logged position_setpoint_triplet's land setpoint carries the altitude PX4's navigator gives
it, not the vehicle's: a mission's land item keeps the item's altitude (the shared PX4 SIH log:
home's, all the way down), Land mode's ``set_land_item`` 0 (AMSL, not relative)."""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.ulog import read_ulog, setpoint_changes
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.mav import MavCmd, Msg
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.uorb import SETPOINT_TYPE_LAND
from uavtest.sitl.vehicle import SimConfig, Vehicle

from .conftest import competition

GCS = (255, 190)


def _land_altitudes(log: ULog) -> np.ndarray:
    tri = log.get_dataset("position_setpoint_triplet").data
    land = (tri["current.type"] == SETPOINT_TYPE_LAND) & (tri["current.valid"] == 1)
    return tri["current.alt"][land]


def test_a_missions_land_setpoint_keeps_the_items_altitude(shared_data: Path) -> None:
    px4 = read_ulog(shared_data / "px4-sih" / "competition-mission1-run1.ulg")
    px4_alt = _land_altitudes(px4)
    home = px4.get_dataset("home_position").data["alt"][-1]
    assert len(px4_alt) >= 1 and np.ptp(px4_alt) < 1e-3  # the oracle: constant (published on change)
    assert px4_alt[0] == pytest.approx(home, abs=0.2)  # the land item's altitude 0: home's

    config, items = competition(shared_data, 1)
    sink = MemorySink()
    fly_mission(config, items, sink=sink)
    ours = _land_altitudes(ULog(io.BytesIO(sink.logs[0])))
    assert len(ours) > 10 and np.ptp(ours) < 1e-3  # was the descending vehicle's altitude
    assert ours[0] == pytest.approx(config.home.alt, abs=1e-3)


def test_land_modes_setpoint_is_at_altitude_zero() -> None:
    sink = MemorySink()
    v = Vehicle(SimConfig(seed=5), sink=sink)

    def command(cmd: int, *params: float) -> None:
        fields: dict[str, object] = {"command": int(cmd), "target_system": 1, "target_component": 1}
        fields.update({f"param{i}": p for i, p in enumerate(params, start=1)})
        v.receive(Msg("COMMAND_LONG", fields, *GCS))

    v.fly_until(lambda v: v.ready, 5_000_000)
    command(MavCmd.COMPONENT_ARM_DISARM, 1)
    command(MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, v.home_alt + 6)
    v.fly_until(lambda v: v.st.z < -5.5, 30_000_000)
    command(MavCmd.NAV_LAND, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)
    v.fly_until(lambda v: v.st.z > -1.0, 30_000_000)
    v.recorder.stop()
    alt = _land_altitudes(ULog(io.BytesIO(sink.logs[0])))
    assert len(alt) > 10 and np.all(alt == 0.0)


def test_an_acceptance_is_logged_the_tick_it_happens(shared_data: Path) -> None:
    """PX4's navigator publishes the new triplet and mission_result the cycle it accepts a
    waypoint, both stamped with that cycle's time (the shared mission2 logs: equal timestamps).
    Analyses align on that moment (``waypoint_passes``, ``braking_velocity_errors``); the log
    once held it back to the next 10 Hz sample and stamped mission_result at the start of the
    clock's slice: 0-100 ms apart."""
    px4 = read_ulog(shared_data / "px4-sih" / "competition-mission2-run1.ulg")
    config, items = competition(shared_data, 2)
    sink = MemorySink()
    fly_mission(config, items, sink=sink)
    ours = ULog(io.BytesIO(sink.logs[0]))
    for log in (px4, ours):
        mr = log.get_dataset("mission_result").data
        reached = mr["timestamp"][np.flatnonzero(np.diff(mr["seq_reached"].astype(int)) > 0) + 1]
        changes = setpoint_changes(log)[:, 0] * 1e6
        assert len(reached) >= 2
        for t in reached:  # every acceptance moves the triplet on at the same microsecond
            assert np.min(np.abs(changes - t)) < 1.0


def test_the_log_does_not_depend_on_the_clock_slices(shared_data: Path) -> None:
    """A flight advanced in 20, 60 or 100 ms slices (a lockstep grant, the in-process loop) writes
    the same log byte for byte: what a tick logs carries the tick's time."""
    config, items = competition(shared_data, 2)
    logs = []
    for sample_us in (20_000, 60_000, 100_000):
        sink = MemorySink()
        fly_mission(config, items, sink=sink, sample_us=sample_us)
        logs.append(sink.logs[0])
    assert logs[0] == logs[1] == logs[2]
