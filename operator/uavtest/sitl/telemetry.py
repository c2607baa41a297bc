"""The telemetry streams PX4 sends, scheduled on the simulated clock.

Rates (Hz) are close to PX4's MAVLink "onboard"/"normal" modes, kept modest so that a
simulator running hundreds of times faster than real time stays cheap; SET_MESSAGE_INTERVAL
changes them. Each stream names the MAVLink message and its id (for SET_MESSAGE_INTERVAL).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DEFAULT_RATES", "MESSAGE_IDS", "Schedule"]

#: message name → default rate in Hz
DEFAULT_RATES: dict[str, float] = {
    "HEARTBEAT": 1.0,
    "SYS_STATUS": 1.0,
    "SYSTEM_TIME": 1.0,
    "EXTENDED_SYS_STATE": 2.0,
    "ATTITUDE": 10.0,
    "LOCAL_POSITION_NED": 10.0,
    "GLOBAL_POSITION_INT": 5.0,
    "HOME_POSITION": 0.5,
    "MISSION_CURRENT": 1.0,
    "VFR_HUD": 2.0,
    "BATTERY_STATUS": 0.5,
    "GPS_RAW_INT": 1.0,
}

#: MAVLink message ids of the streams (common.xml)
MESSAGE_IDS: dict[int, str] = {
    0: "HEARTBEAT",
    1: "SYS_STATUS",
    2: "SYSTEM_TIME",
    24: "GPS_RAW_INT",
    30: "ATTITUDE",
    32: "LOCAL_POSITION_NED",
    33: "GLOBAL_POSITION_INT",
    42: "MISSION_CURRENT",
    74: "VFR_HUD",
    147: "BATTERY_STATUS",
    242: "HOME_POSITION",
    245: "EXTENDED_SYS_STATE",
}


@dataclass(slots=True)
class _Stream:
    name: str
    interval_us: int  # 0: off
    next_us: int


class Schedule:
    """Which streams are due at a time; intervals in microseconds of vehicle time."""

    def __init__(self, rates: dict[str, float] | None = None) -> None:
        rates = dict(DEFAULT_RATES if rates is None else rates)
        self._streams = [_Stream(name, round(1e6 / hz) if hz > 0 else 0, 0) for name, hz in rates.items()]
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

    def set_interval(self, message_id: int, interval_us: int, now_us: int) -> bool:
        """SET_MESSAGE_INTERVAL: -1 off, 0 default, else microseconds. False for unknown messages."""
        name = MESSAGE_IDS.get(message_id)
        if name is None:
            return False
        stream = self._by_name.get(name)
        if interval_us == 0:
            hz = DEFAULT_RATES[name]
            interval_us = round(1e6 / hz)
        elif interval_us < 0:
            interval_us = 0
        if stream is None:
            stream = _Stream(name, interval_us, now_us)
            self._streams.append(stream)
            self._by_name[name] = stream
        stream.interval_us = max(interval_us, 0)
        stream.next_us = now_us
        self.next_due = now_us
        return True
