"""A vehicle that rebooted under the runner (pure): no verdict on a half flight.

A simulator that crashes and is started again (a Kubernetes sidecar restarts by itself, on the
same port) is a new vehicle: time since boot from zero, disarmed, none of the test's parameters or
mission. What the runner would see next — a disarmed vehicle on the ground — looks like a landing,
and the log would hold half a flight. The vehicle clock tells: every message the runner reads
carries ``time_boot_ms`` (LOCAL_POSITION_NED, GLOBAL_POSITION_INT, SYSTEM_TIME, the lockstep
announce), and within one boot it only moves forward.

- Telemetry may arrive a little out of order (each stream stamps its own topic's sample), so a
  stamp counts as a reboot only when it is more than ``JITTER_MS`` behind the latest one.
- A lockstep announce is the simulator's own clock, exact: any step back is a reboot.

A heartbeat alone cannot tell a fresh boot from a landing (PX4 reports MAV_STATE_UNINIT whenever
its preflight checks fail, e.g. after a GPS loss, and disarms on landing), so the core waits for
the clock to move on after a disarm before it calls it a landing (``uavtest.runner.core``); a new
boot's clock never does.
"""

from __future__ import annotations

__all__ = ["JITTER_MS", "clock_went_back", "reboot_reason"]

JITTER_MS = 1000  # how far a telemetry stamp may lag the latest one within one boot


def clock_went_back(latest_ms: int, seen_ms: int, *, jitter_ms: int = JITTER_MS) -> bool:
    """Whether a message stamped ``seen_ms`` comes from a new boot of a vehicle whose clock had
    reached ``latest_ms`` (more than ``jitter_ms`` behind it)."""
    return seen_ms < latest_ms - jitter_ms


_WHEN = {
    "params": ("while the runner set its parameters", "the test's parameters are gone"),
    "mission": ("while the runner uploaded the mission", "the test's parameters and mission are gone"),
    "flight": ("mid-flight", "no verdict on a half flight"),
    "log": ("while its log was downloaded", "no verdict on a log that may be another boot's"),
}


def reboot_reason(stage: str, latest_ms: int, seen_ms: int) -> str:
    """The replica's error reason, e.g. 'the vehicle rebooted mid-flight (time since boot went
    from 41.2 s to 0.8 s): simulator restarted; no verdict on a half flight'."""
    when, consequence = _WHEN.get(stage, (f"during {stage}", "no verdict"))
    return (
        f"the vehicle rebooted {when} (time since boot went from {latest_ms / 1000:.1f} s "
        f"to {seen_ms / 1000:.1f} s): simulator restarted; {consequence}"
    )
