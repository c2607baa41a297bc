"""Our flight log read back with pyulog (and the analysis) like a PX4 log."""

import io
from pathlib import Path

import pytest
from pyulog import ULog

from uavtest.analysis.ulog import flight_window, mission_progress_from_ulog
from uavtest.sitl.inprocess import fly_mission
from uavtest.sitl.main import FileLogSink
from uavtest.sitl.recorder import MemorySink

PX4_TOPICS = {
    "vehicle_local_position",
    "vehicle_global_position",
    "vehicle_status",
    "vehicle_land_detected",
    "vehicle_command",
    "position_setpoint_triplet",
    "vehicle_attitude",
    "mission_result",
    "home_position",
}


@pytest.fixture(scope="module")
def flown(shared_data: Path) -> tuple[ULog, float]:
    from .conftest import competition

    config, items = competition(shared_data, 2)
    sink = MemorySink()
    flight = fly_mission(config, items, sink=sink)
    assert len(sink.logs) == 1, "one log from boot to disarm"
    assert flight.flight_time is not None
    return ULog(io.BytesIO(sink.logs[0])), flight.flight_time


def test_px4_topics_and_fields(flown):
    ulog, _ = flown
    names = {d.name for d in ulog.data_list}
    assert names >= PX4_TOPICS
    lp = ulog.get_dataset("vehicle_local_position").data
    assert {
        "timestamp",
        "x",
        "y",
        "z",
        "vx",
        "vy",
        "vz",
        "heading",
        "xy_valid",
        "z_valid",
        "ref_lat",
    } <= lp.keys()
    assert (lp["timestamp"][1:] > lp["timestamp"][:-1]).all()
    assert lp["z"].min() < -9.5
    status = ulog.get_dataset("vehicle_status").data
    assert {1, 2} <= set(status["arming_state"]) and 3 in set(status["nav_state"])  # armed, AUTO_MISSION
    triplet = ulog.get_dataset("position_setpoint_triplet").data
    assert {
        "current.lat",
        "current.lon",
        "current.alt",
        "current.valid",
        "next.valid",
        "previous.type",
    } <= triplet.keys()
    assert ulog.get_dataset("vehicle_attitude").data["q[0]"].size > 0


def test_parameters_and_messages(flown):
    ulog, _ = flown
    assert ulog.initial_parameters["NAV_ACC_RAD"] == pytest.approx(0.5)
    assert isinstance(ulog.initial_parameters["MPC_YAW_MODE"], int)
    texts = [m.message for m in ulog.logged_messages]
    assert "Takeoff detected" in texts and "Landing detected" in texts
    assert ulog.msg_info_dict["sys_name"] == "PX4"


def test_the_analysis_reads_it_like_px4(flown):
    ulog, flight_time = flown
    window = flight_window(ulog)
    assert window.source == "vehicle_land_detected" and window.landed
    assert window.duration == pytest.approx(flight_time, abs=0.05)
    progress = mission_progress_from_ulog(ulog)
    assert progress is not None and progress.finished and progress.reached == progress.total == 3


def test_file_sink_renames_part_when_closed(tmp_path: Path, shared_data: Path):
    from .conftest import competition

    config, items = competition(shared_data, 1)
    sink = FileLogSink(tmp_path, seed=3)
    fly_mission(config, items, sink=sink)
    assert [p.name for p in tmp_path.iterdir()] == ["seed3-1.ulg"]
    ULog(str(tmp_path / "seed3-1.ulg"))  # parses
