"""The telemetry streams PX4 sends, per MAVLink link, scheduled on the simulated clock.

PX4 gives each MAVLink instance a mode whose default stream rates come from
``src/modules/mavlink/mavlink_main.cpp`` ``Mavlink::configure_streams_to_default``; PX4 SITL
(``ROMFS/px4fmu_common/init.d-posix/px4-rc.mavlink``) starts the GCS link (local 18570, remote
14550) in mode NORMAL with some streams raised to 50 Hz (``mavlink stream -r 50``), and the
API/offboard link (local 14580, remote 14540) in mode ONBOARD. ``MODES`` holds those tables,
restricted to the messages the built-in vehicle builds (``mavlink_streams.STREAMS``).

Rates above the 50 Hz control tick (ONBOARD ATTITUDE at 100 Hz) are sent once per tick: 50 Hz.
PX4's "unlimited" rate (a message per uORB update) is the sensor's rate: GPS_RAW_INT at the
simulated GPS's 10 Hz. HEARTBEAT is sent at 1 Hz on every link whatever the mode (PX4
``Mavlink::task_main`` sends it itself) and cannot be changed by SET_MESSAGE_INTERVAL
(``MavlinkReceiver::set_message_interval`` refuses message id 0). DISTANCE_SENSOR and
OBSTACLE_DISTANCE are configured on every link, as in PX4, but a stream sends only when its topic
has news (a range sensor; Collision Prevention running): their builders may return None.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DEFAULT_RATES", "MESSAGE_IDS", "MODES", "NORMAL", "ONBOARD", "Schedule"]

NORMAL = "normal"
ONBOARD = "onboard"

#: mode → message name → default rate in Hz (mavlink_main.cpp configure_streams_to_default)
MODES: dict[str, dict[str, float]] = {
    NORMAL: {
        "HEARTBEAT": 1.0,
        "ALTITUDE": 1.0,
        "ATTITUDE": 15.0,
        "ATTITUDE_QUATERNION": 10.0,
        "BATTERY_STATUS": 0.5,
        "EXTENDED_SYS_STATE": 1.0,
        "GLOBAL_POSITION_INT": 5.0,
        "GPS_RAW_INT": 5.0,
        "HOME_POSITION": 0.5,
        "LOCAL_POSITION_NED": 1.0,
        "MISSION_CURRENT": 1.0,  # MavlinkMissionManager, not a configured stream
        "SCALED_PRESSURE": 1.0,
        "SYS_STATUS": 1.0,
        "VFR_HUD": 4.0,
        "WIND_COV": 0.5,
        "DISTANCE_SENSOR": 0.5,  # sent only with a range sensor
        "OBSTACLE_DISTANCE": 1.0,  # sent only while Collision Prevention runs
    },
    ONBOARD: {
        "HEARTBEAT": 1.0,
        "HIGHRES_IMU": 50.0,
        "LOCAL_POSITION_NED": 30.0,
        "ATTITUDE": 100.0,
        "ALTITUDE": 10.0,
        "ODOMETRY": 30.0,
        "ATTITUDE_QUATERNION": 50.0,
        "BATTERY_STATUS": 0.5,
        "EXTENDED_SYS_STATE": 5.0,
        "GLOBAL_POSITION_INT": 50.0,
        "GPS_RAW_INT": 10.0,  # unlimited: every GPS update
        "HOME_POSITION": 0.5,
        "MISSION_CURRENT": 1.0,
        "SCALED_PRESSURE": 1.0,
        "SYS_STATUS": 5.0,
        "SYSTEM_TIME": 1.0,
        "VFR_HUD": 10.0,
        "WIND_COV": 10.0,
        "DISTANCE_SENSOR": 10.0,
        "OBSTACLE_DISTANCE": 10.0,
    },
}

#: px4-rc.mavlink: the SITL GCS link's ``mavlink stream -r 50 -s ...`` on top of NORMAL
SITL_GCS_RATES: dict[str, float] = {
    **MODES[NORMAL],
    "LOCAL_POSITION_NED": 50.0,
    "GLOBAL_POSITION_INT": 50.0,
    "ATTITUDE": 50.0,
    "ATTITUDE_QUATERNION": 50.0,
}
MODES["sitl_gcs"] = SITL_GCS_RATES

#: the single link of an in-process vehicle (what a PX4 API client on 14540 receives)
DEFAULT_RATES = MODES[ONBOARD]

#: MAVLink message ids of the streams (common.xml)
MESSAGE_IDS: dict[int, str] = {
    0: "HEARTBEAT",
    1: "SYS_STATUS",
    2: "SYSTEM_TIME",
    24: "GPS_RAW_INT",
    29: "SCALED_PRESSURE",
    30: "ATTITUDE",
    31: "ATTITUDE_QUATERNION",
    32: "LOCAL_POSITION_NED",
    33: "GLOBAL_POSITION_INT",
    42: "MISSION_CURRENT",
    74: "VFR_HUD",
    105: "HIGHRES_IMU",
    132: "DISTANCE_SENSOR",
    141: "ALTITUDE",
    147: "BATTERY_STATUS",
    231: "WIND_COV",
    242: "HOME_POSITION",
    245: "EXTENDED_SYS_STATE",
    330: "OBSTACLE_DISTANCE",
    331: "ODOMETRY",
}
_ID_OF = {name: mid for mid, name in MESSAGE_IDS.items()}


@dataclass(slots=True)
class _Stream:
    name: str
    interval_us: int  # 0: off
    next_us: int


class Schedule:
    """Which streams are due at a time on one link; intervals in microseconds of vehicle time."""

    def __init__(self, rates: dict[str, float] | None = None) -> None:
        self.defaults = dict(DEFAULT_RATES if rates is None else rates)
        self._streams = [
            _Stream(name, round(1e6 / hz) if hz > 0 else 0, 0) for name, hz in self.defaults.items()
        ]
        self._by_name = {s.name: s for s in self._streams}
        self.next_due = 0

    def due(self, now_us: int) -> list[str]:
        """Names of the streams due at ``now_us`` (each advanced to its next slot)."""
        if now_us < self.next_due:
            return []
        names = []
        nxt = 1 << 62
        for s in self._streams:
            if s.interval_us <= 0:
                continue
            if s.next_us <= now_us:
                names.append(s.name)
                s.next_us += s.interval_us
                if s.next_us <= now_us:
                    s.next_us = now_us + s.interval_us
            if s.next_us < nxt:
                nxt = s.next_us
        self.next_due = nxt
        return names

    def set_interval(self, message_id: int, interval_us: float, now_us: int) -> bool:
        """SET_MESSAGE_INTERVAL as ``MavlinkReceiver::set_message_interval``: -1 (any negative)
        stops the stream, 0 restores this link's default, else microseconds. False (the command
        FAILED) for HEARTBEAT and for messages the vehicle does not stream."""
        name = MESSAGE_IDS.get(message_id)
        if name is None or name == "HEARTBEAT":
            return False
        if interval_us < -0.00001:
            interval = 0
        elif interval_us > 0.00001:
            interval = max(round(interval_us), 1)
        else:
            hz = self.defaults.get(name, 0.0)
            interval = round(1e6 / hz) if hz > 0 else 0
        stream = self._by_name.get(name)
        if stream is None:
            stream = _Stream(name, interval, now_us)
            self._streams.append(stream)
            self._by_name[name] = stream
        stream.interval_us = interval
        stream.next_us = now_us
        self.next_due = now_us
        return True

    def interval(self, message_id: int) -> int:
        """MESSAGE_INTERVAL.interval_us as PX4's ``get_message_interval``: the stream's interval,
        0 when the message is not streamed on this link (stopped or never configured)."""
        stream = self._by_name.get(MESSAGE_IDS.get(message_id, ""))
        return stream.interval_us if stream is not None else 0
