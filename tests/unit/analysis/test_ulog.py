"""ULog → flight trajectory, checked against what the real logs show independently.

Expected values come from the data's README (square mission: armed 134.2 s, takeoff detected
136.0 s, landed 176.2 s; px4-sih flight times 41.4 / 47.0 / 41.0 s and 72.2 / 60.5 / 71.7 s)
and from reading the logs' topics directly with pyulog.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from uavtest.analysis.ulog import (
    VERDICT_TOPICS,
    crash_reported,
    flight_window,
    mission_progress_from_ulog,
    read_ulog,
    trajectory_from_ulog,
)
from uavtest.errors import BadInput, MissingFile

NO_FLIGHT_LOGS = [
    "sample.ulg",
    "sample_appended_multiple.ulg",
    "sample_logging_tagged_and_default_params.ulg",
]


def test_square_mission_is_cut_at_takeoff_and_landing(square_log: ULog) -> None:
    w = flight_window(square_log)
    assert w.source == "vehicle_land_detected"
    assert w.start == pytest.approx(136.0, abs=0.1)
    assert w.end == pytest.approx(176.2, abs=0.1)
    assert w.landed
    tr = trajectory_from_ulog(square_log, w)
    assert tr.t[0] >= w.start and tr.t[-1] <= w.end
    assert tr.duration == pytest.approx(40.2, abs=0.1)


def test_square_mission_flies_the_square_relative_to_home(square_log: ULog) -> None:
    tr = trajectory_from_ulog(square_log)
    # takeoff to 10 m above home (the estimator's ground drifts by metres before arming: home removes it)
    assert tr.altitude.max() == pytest.approx(10.0, abs=0.5)
    assert np.hypot(tr.x[0], tr.y[0]) < 1.0  # takes off at home
    for north, east in [(30, 0), (30, 30)]:
        assert np.hypot(tr.x - north, tr.y - east).min() < 1.0
    assert np.hypot(tr.x[-1] - 30, tr.y[-1] - 30) < 1.0  # lands at the last waypoint


def test_square_mission_result_counts_all_four_items(square_log: ULog) -> None:
    progress = mission_progress_from_ulog(square_log)
    assert progress is not None
    assert (progress.reached, progress.total, progress.finished) == (4, 4, True)


def test_without_land_detector_the_flight_is_cut_by_arming(shared_data: Path) -> None:
    ulog = read_ulog(
        shared_data / "px4-sih" / "square-mission.ulg", ["vehicle_local_position", "vehicle_status"]
    )
    w = flight_window(ulog)
    assert w.source == "arming"
    assert w.start == pytest.approx(134.2, abs=0.1)
    assert w.end == pytest.approx(176.2, abs=0.1)


def test_without_land_detector_or_arming_the_motion_cuts_the_flight(shared_data: Path) -> None:
    for name in ["square-mission.ulg", "competition-mission1-run1.ulg", "competition-mission2-run2.ulg"]:
        full = flight_window(read_ulog(shared_data / "px4-sih" / name))
        ulog = read_ulog(shared_data / "px4-sih" / name, ["vehicle_local_position"])
        w = flight_window(ulog)
        assert w.source == "motion"
        assert w.start == pytest.approx(full.start, abs=3.0), name
        assert w.end == pytest.approx(full.end, abs=3.0), name


def test_aerialist_real_flight(aerialist_log: ULog) -> None:
    # armed when the log starts (670.3 s), airborne 672.2–712.2 s, disarmed 712.7 s: a 43 s log
    w = flight_window(aerialist_log)
    assert w.start == pytest.approx(672.25, abs=0.05)
    assert w.end == pytest.approx(712.19, abs=0.05)
    tr = trajectory_from_ulog(aerialist_log, w)
    assert tr.duration == pytest.approx(39.9, abs=0.2)
    assert 10 * tr.duration == pytest.approx(len(tr), abs=3)  # vehicle_local_position at 10 Hz
    # v1.12 mission_result resets after landing: the mission still counts as completed
    progress = mission_progress_from_ulog(aerialist_log)
    assert progress is not None and progress.finished and progress.total == 2


@pytest.mark.parametrize(
    ("name", "flight_time"),
    [
        ("competition-mission1-run1.ulg", 41.4),
        ("competition-mission1-run2.ulg", 47.0),
        ("competition-mission1-run3.ulg", 41.0),
        ("competition-mission2-run1.ulg", 72.2),
        ("competition-mission2-run2.ulg", 60.5),
        ("competition-mission2-run3.ulg", 71.7),
    ],
)
def test_px4_sih_flight_times_match_the_data_readme(shared_data: Path, name: str, flight_time: float) -> None:
    tr = trajectory_from_ulog(read_ulog(shared_data / "px4-sih" / name))
    assert tr.duration == pytest.approx(flight_time, abs=0.1)
    assert tr.altitude.max() == pytest.approx(10.0, abs=0.5)


@pytest.mark.parametrize("name", NO_FLIGHT_LOGS)
def test_logs_that_never_took_off_give_an_empty_flight(shared_data: Path, name: str) -> None:
    ulog = read_ulog(shared_data / "pyulog" / name)
    w = flight_window(ulog)
    assert not w.took_off
    assert trajectory_from_ulog(ulog, w).empty


def test_appended_and_tagged_logs_are_read_whole(shared_data: Path) -> None:
    # counts of vehicle_local_position samples as pyulog reads them; appended data included
    appended = read_ulog(shared_data / "pyulog" / "sample_appended_multiple.ulg")
    tagged = read_ulog(shared_data / "pyulog" / "sample_logging_tagged_and_default_params.ulg")
    lengths = {
        ulog_name: [len(d.data["timestamp"]) for d in u.data_list if d.name == "vehicle_local_position"]
        for ulog_name, u in (("appended", appended), ("tagged", tagged))
    }
    assert lengths == {"appended": [95], "tagged": [1268]}


def test_events_log_flight(shared_data: Path) -> None:
    tr = trajectory_from_ulog(read_ulog(shared_data / "pyulog" / "sample_px4_events.ulg"))
    assert tr.duration == pytest.approx(11.3, abs=0.2)
    assert tr.altitude.max() == pytest.approx(2.1, abs=0.2)


def test_log_without_local_position_names_the_file(shared_data: Path) -> None:
    path = shared_data / "px4-sih" / "square-mission.ulg"
    ulog = read_ulog(path, ["vehicle_status"])
    with pytest.raises(BadInput, match=r"square-mission\.ulg.*vehicle_local_position"):
        trajectory_from_ulog(ulog, source=str(path))


def test_missing_and_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(MissingFile, match=r"nope\.ulg"):
        read_ulog(tmp_path / "nope.ulg")
    junk = tmp_path / "junk.ulg"
    junk.write_bytes(b"this is not a ULog at all" * 10)
    with pytest.raises(BadInput, match=r"junk\.ulg"):
        read_ulog(junk)


def test_a_land_detector_that_let_go_on_the_ground_is_no_flight(tmp_path: Path) -> None:
    """PX4's land detector says "not landed" during the takeoff ramp: a takeoff cut short on the
    ground (a land or disarm 0.5 s later, seen on PX4 SITL) must not count as a flight."""
    from uavtest.analysis.ulog import flight_window
    from uavtest.sitl.ulog_writer import ULogEncoder
    from uavtest.sitl.uorb import FORMATS

    def record(topic: str, **values: float) -> list[float]:
        names = [f.split(" ")[1] for f in FORMATS[topic]]
        return [values.get(n, 0) for n in names]

    def log(z_peak: float) -> ULog:
        enc = ULogEncoder(FORMATS)
        data = bytearray(
            enc.header(0, {"sys_name": "PX4"}, [], ["vehicle_local_position", "vehicle_land_detected"])
        )
        for k in range(100):  # 10 s at 10 Hz; "in the air" from 4 s to 6.6 s
            t = k * 100_000
            air = 4_000_000 <= t < 6_600_000
            z = -z_peak if 4_500_000 <= t < 6_000_000 else 0.0
            data += enc.data("vehicle_local_position", record("vehicle_local_position", timestamp=t, z=z))
            data += enc.data(
                "vehicle_land_detected", record("vehicle_land_detected", timestamp=t, landed=not air)
            )
        path = tmp_path / f"hop-{z_peak}.ulg"
        path.write_bytes(bytes(data))
        return ULog(str(path))

    hop = flight_window(log(0.003))
    assert not hop.took_off and hop.source == "vehicle_land_detected"
    flight = flight_window(log(2.0))
    assert flight.took_off and flight.start == pytest.approx(4.0) and flight.end == pytest.approx(6.6)


@pytest.mark.parametrize(
    "name",
    [
        "px4-sih/square-mission.ulg",
        "px4-sih/competition-mission2-run1.ulg",
        "pyulog/sample_px4_events.ulg",
        "aerialist/samples/flights/mission1.ulg",
    ],
)
def test_the_verdict_topics_alone_give_the_verdicts_inputs(shared_data: Path, name: str) -> None:
    """The runner parses only VERDICT_TOPICS: the flight's cut, its trajectory relative to home,
    the mission's progress and a crash text come out as from the whole log."""
    whole = read_ulog(shared_data / name)
    some = read_ulog(shared_data / name, VERDICT_TOPICS)
    assert len(some.data_list) < len(whole.data_list)
    a, b = trajectory_from_ulog(whole), trajectory_from_ulog(some)
    assert len(a) > 0
    for field in ("t", "x", "y", "z"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert mission_progress_from_ulog(some) == mission_progress_from_ulog(whole)
    assert crash_reported(some) == crash_reported(whole)
    assert flight_window(some) == flight_window(whole)
