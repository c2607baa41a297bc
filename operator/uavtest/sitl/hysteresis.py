"""PX4's ``systemlib::Hysteresis`` (``src/lib/hysteresis/hysteresis.cpp``): a boolean that takes
a new value only once it has been asked for it for long enough.

The time runs from the first request of the new value; asking for the current value again
cancels the request. Times are in microseconds, as PX4's ``hrt_abstime``.
"""

from __future__ import annotations

__all__ = ["Hysteresis"]


class Hysteresis:
    def __init__(self, state: bool = False) -> None:
        self.state = state
        self._requested = state
        self._since_us = 0
        self.time_from_false_us = 0
        self.time_from_true_us = 0

    def set_hysteresis_time_from(self, from_state: bool, time_us: int) -> None:
        """``set_hysteresis_time_from``: how long a change away from ``from_state`` must be asked for."""
        if from_state:
            self.time_from_true_us = time_us
        else:
            self.time_from_false_us = time_us

    def set_state_and_update(self, new_state: bool, now_us: int) -> None:
        """``set_state_and_update``: ask for ``new_state`` (its time starts at the first request)."""
        if new_state != self.state:
            if new_state != self._requested:
                self._requested = new_state
                self._since_us = now_us
        else:
            self._requested = self.state
        self.update(now_us)

    def update(self, now_us: int) -> None:
        """``update``: take the requested value once it has been asked for long enough."""
        if self._requested == self.state:
            return
        wait = self.time_from_true_us if self.state else self.time_from_false_us
        if now_us >= self._since_us + wait:
            self.state = self._requested
