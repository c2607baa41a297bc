"""Our flight log read back with pyulog (and the analysis) like a PX4 log."""

import io
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.ulog import flight_window, mission_progress_from_ulog, read_ulog
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


def _triplets(ulog: ULog) -> list[tuple]:
    """The distinct (previous, current, next) of position_setpoint_triplet while flying legs:
    validity and latitude (rounded to a centimetre) of each."""
    d = ulog.get_dataset("position_setpoint_triplet").data
    seen: list[tuple] = []
    for i in range(len(d["timestamp"])):
        if d["current.type"][i] != 0:  # SETPOINT_TYPE_POSITION: a leg
            continue
        row = tuple(
            (bool(d[f"{s}.valid"][i]), round(float(d[f"{s}.lat"][i]), 7) if d[f"{s}.valid"][i] else None)
            for s in ("previous", "current", "next")
        )
        if not seen or seen[-1] != row:
            seen.append(row)
    return seen


def test_the_triplet_names_the_track_and_the_corner_as_px4_logs_them(flown, shared_data: Path):
    """PX4's navigator publishes the waypoint just reached as ``previous`` and the one after the
    target as ``next`` (mission2: out to the waypoint with the landing point next, then back to the
    landing point from the waypoint); FlightTaskAuto flies the track between them. Analyses that
    read a PX4 log's legs read ours."""
    px4 = _triplets(read_ulog(shared_data / "px4-sih" / "competition-mission2-run2.ulg"))
    ours = _triplets(flown[0])
    legs = [r for r in ours if r[0][0]]  # with a previous waypoint
    assert len(legs) >= 2
    out, back = legs[0], legs[-1]
    assert out[2][0], "the first leg's triplet carries the corner after it (next)"
    assert back[0][1] == out[1][1], "the way back starts at the waypoint just reached"
    # the takeoff has no track: no previous waypoint, as in PX4's log
    d = flown[0].get_dataset("position_setpoint_triplet").data
    takeoff = d["current.type"] == 3  # SETPOINT_TYPE_TAKEOFF
    assert takeoff.any() and not d["previous.valid"][takeoff].any()
    # PX4 logged the same structure for the same plan (positions to within a metre: 1e-5 deg)
    px4_legs = [r for r in px4 if r[0][0]]
    assert px4_legs[-1][0][1] == pytest.approx(back[0][1], abs=1e-5)
    assert any(r[2][0] for r in px4_legs)


def test_position_control_setpoints_are_logged_like_px4s(flown):
    """vehicle_local_position_setpoint: PositionControl's acceleration and normalised thrust
    setpoints (a hover asks for MPC_THR_HOVER upwards, 0.5 in SIH's airframe)."""
    ulog, _ = flown
    sp = ulog.get_dataset("vehicle_local_position_setpoint").data
    assert {"acceleration[0]", "thrust[2]", "vx", "yaw"} <= sp.keys()
    assert float(np.median(sp["thrust[2]"])) == pytest.approx(-0.5, abs=0.05)
    tilt = np.hypot(sp["thrust[0]"], sp["thrust[1]"])
    assert tilt.max() > 0.1, "the legs ask for horizontal thrust"


def test_the_truth_is_logged_next_to_the_estimate_as_px4_sitl_does(flown):
    """vehicle_local_position_groundtruth and vehicle_attitude_groundtruth, as PX4 SITL logs
    them: the estimate differs from the truth by EKF2-like errors (decimetres, a few degrees of
    heading), so a user can tell what the vehicle believed from where it was."""
    ulog, _ = flown
    lp = ulog.get_dataset("vehicle_local_position").data
    gt = ulog.get_dataset("vehicle_local_position_groundtruth").data
    assert gt.keys() == lp.keys()
    t = gt["timestamp"]
    err = np.hypot(
        np.interp(t, lp["timestamp"], lp["x"]) - gt["x"], np.interp(t, lp["timestamp"], lp["y"]) - gt["y"]
    )
    assert 0.01 < float(np.median(err)) < 0.5
    assert float(gt["z"].min()) < -9.0
    est = ulog.get_dataset("vehicle_attitude").data
    truth = ulog.get_dataset("vehicle_attitude_groundtruth").data
    assert len(truth["q[0]"]) == len(est["q[0]"])
    assert not np.allclose(truth["q[3]"], est["q[3]"]), "EKF2's heading error shows in the estimate"
