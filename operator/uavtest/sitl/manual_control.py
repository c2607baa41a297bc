"""PX4's ManualControl module (``src/modules/manual_control``): is the pilot moving the sticks?

``ManualControl::processInput`` (PX4 v1.15) sets ``manual_control_setpoint.sticks_moving`` when
any stick (roll, pitch, yaw, throttle; each in [-1, 1]) changes faster than ``COM_RC_STICK_OV``
percent of full deflection per second: each stick's rate of change (``MovingDiff``) is
low-passed with a 0.1 s time constant (``AlphaFilter``). The module runs on each new sample and,
without one, every 200 ms (its timeout schedule), so a held stick's rate decays to zero between
samples. The commander turns a moving stick into a takeover (``COM_RC_OVERRIDE``).
"""

from __future__ import annotations

import math

__all__ = ["MovingDiff", "StickMovement"]

_TIME_CONSTANT_S = 0.1  # MovingDiff: _difference_filter.setParameters(dt_s, .1f)
_TIMEOUT_S = 0.2  # ManualControl: ScheduleDelayed(200_ms) when no sample comes
_FLT_EPSILON = 1.1920929e-07


class MovingDiff:
    """``MovingDiff``: the low-passed rate of change of one stick (per second)."""

    def __init__(self) -> None:
        self._state = 0.0
        self._last = math.nan

    def update(self, value: float, dt_s: float) -> float:
        if not math.isfinite(value) or dt_s < _FLT_EPSILON:
            return math.nan
        if math.isfinite(self._last):
            alpha = dt_s / (_TIME_CONSTANT_S + dt_s)  # AlphaFilter::setParameters
            self._state += alpha * ((value - self._last) / dt_s - self._state)
        self._last = value
        return self._state


class StickMovement:
    """The four sticks' ``MovingDiff`` and the ``sticks_moving`` decision, fed per sample."""

    def __init__(self) -> None:
        self._diffs = [MovingDiff() for _ in range(4)]
        self._last_us: int | None = None
        self._held: tuple[float, float, float, float] | None = None

    def update(
        self,
        t_us: int,
        sticks: tuple[float, float, float, float],
        threshold_pct: float,
        loss_timeout_s: float = math.inf,
    ) -> bool:
        """``sticks``: roll, pitch, yaw, throttle in [-1, 1]; ``threshold_pct``: COM_RC_STICK_OV.
        True when one of them moves faster than the threshold (per second). After a gap longer
        than ``loss_timeout_s`` (COM_RC_LOSS_T) the input was invalid and the rates were reset
        (``MovingDiff::reset``): sticks that come back elsewhere are not a movement."""
        dt = 0.0 if self._last_us is None else (t_us - self._last_us) / 1e6
        if dt > loss_timeout_s:
            self._diffs = [MovingDiff() for _ in range(4)]
            self._held = None
        if self._held is not None and dt > _TIMEOUT_S:
            # the module's runs on its 200 ms timeout between samples, with the held sticks
            runs = math.ceil(dt / _TIMEOUT_S) - 1
            for _ in range(min(runs, 10)):
                for diff, value in zip(self._diffs, self._held, strict=True):
                    diff.update(value, _TIMEOUT_S)
            dt = dt - runs * _TIMEOUT_S if runs <= 10 else _TIMEOUT_S
        self._last_us = t_us
        self._held = sticks
        minimum_change = 0.01 * threshold_pct
        rates = [diff.update(value, dt) for diff, value in zip(self._diffs, sticks, strict=True)]
        return any(abs(rate) > minimum_change for rate in rates)  # NaN compares False
