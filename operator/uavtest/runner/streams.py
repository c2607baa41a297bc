"""The telemetry the runner asks its vehicle for (SET_MESSAGE_INTERVAL), as any MAVLink client may.

PX4 streams its ONBOARD link's defaults from boot (~300 messages per second: ATTITUDE at 100 Hz,
HIGHRES_IMU and GLOBAL_POSITION_INT at 50 Hz, ODOMETRY at 30 Hz, ...). The runner reads only
heartbeats, SYS_STATUS, SYSTEM_TIME, LOCAL_POSITION_NED, GLOBAL_POSITION_INT (for the fix),
HOME_POSITION (0.5 Hz, checked against world.home), EXTENDED_SYS_STATE, STATUSTEXT and the
answers of the protocols it runs; the flight itself is judged from the ULog. So once connected
it stops the streams it never reads and slows GLOBAL_POSITION_INT, on PX4 and on the built-in
simulator alike: less work for both, the same flight. The requests are sent once and not
awaited: a vehicle that refuses one (an older PX4 without that stream) flies the same, only
with more telemetry. A runner that sends PX4 a range sensor's scans (``uavtest.runner.obstacle_distance``)
keeps ATTITUDE, at ``ATTITUDE_INTERVAL_US``, for the heading its scans turn with.
"""

from __future__ import annotations

from uavtest.mavlink_numbers import MavCmd
from uavtest.runner.events import CommandLong

__all__ = ["ATTITUDE_INTERVAL_US", "STREAM_INTERVALS_US", "stream_requests"]

OFF = -1.0
ATTITUDE_INTERVAL_US = 20_000.0  # 50 Hz of vehicle time: the heading of a 10-50 Hz scan

#: message id → interval in µs (-1: stop the stream), per MAV_CMD_SET_MESSAGE_INTERVAL
STREAM_INTERVALS_US: dict[int, float] = {
    24: OFF,  # GPS_RAW_INT
    29: OFF,  # SCALED_PRESSURE
    30: OFF,  # ATTITUDE
    31: OFF,  # ATTITUDE_QUATERNION
    33: 200_000.0,  # GLOBAL_POSITION_INT: 5 Hz is plenty to see the global fix
    74: OFF,  # VFR_HUD
    105: OFF,  # HIGHRES_IMU
    141: OFF,  # ALTITUDE
    147: OFF,  # BATTERY_STATUS
    231: OFF,  # WIND_COV
    331: OFF,  # ODOMETRY
}


def stream_requests(*, attitude: bool = False) -> list[CommandLong]:
    """One SET_MESSAGE_INTERVAL per stream in ``STREAM_INTERVALS_US``; ``attitude`` keeps ATTITUDE
    (id 30) at ``ATTITUDE_INTERVAL_US``."""
    intervals = dict(STREAM_INTERVALS_US)
    if attitude:
        intervals[30] = ATTITUDE_INTERVAL_US
    return [
        CommandLong(MavCmd.SET_MESSAGE_INTERVAL, (float(msg_id), interval, 0.0, 0.0, 0.0, 0.0, 0.0))
        for msg_id, interval in intervals.items()
    ]
