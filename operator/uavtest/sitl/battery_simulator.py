"""The simulated battery: PX4's ``battery_simulator`` feeding PX4's battery library.

``src/modules/simulation/battery_simulator/BatterySimulator.cpp`` (what PX4 SITL runs) makes the
voltage: while armed the charge falls linearly from full to empty in ``SIM_BAT_DRAIN`` seconds,
never below ``SIM_BAT_MIN_PCT``; disarmed it is full again; the cell voltage is interpolated between
``BAT1_V_EMPTY`` and ``BAT1_V_CHARGED`` and times ``BAT1_N_CELLS``; there is no current sensor
(current -1). MAV_CMD_INJECT_FAILURE on SYSTEM_BATTERY instance 0: OFF forces the empty voltage,
OK restores it (other instances: UNSUPPORTED; other types: not handled here).

``src/lib/battery/battery.cpp`` turns it into ``battery_status``: a voltage filter (AlphaFilter,
1 s), "connected" above 2.1 V and initialised 2 s later; the state of charge is voltage based
(``BAT1_CAPACITY`` -1 in SITL), with the load drop compensated by throttle when the current is
unknown: ``cell_voltage += throttle * BAT1_V_LOAD_DROP`` (filtered, 1 s). That is the only thrust
dependence PX4 SITL has: the simulator's voltage does not sag, so the estimate reads *higher*
while the motors work. The throttle is the collective thrust normalised by ``MPC_THR_HOVER``
(thrust in g times the hover throttle), as PX4's ``vehicle_thrust_setpoint`` is around hover.
The warning level is ``BAT_LOW_THR`` / ``BAT_CRIT_THR`` / ``BAT_EMERGEN_THR`` against the state
of charge (``Battery::determineWarning``).

PX4 samples at 100 Hz; the built-in vehicle at 5 Hz (the filters use the real interval; the
topic is logged at PX4's 5 Hz logger rate), which changes nothing a client sees but when a
threshold is crossed (at most 0.2 s later): the charge falls by 0.2 % per sample at a 100 s drain.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from uavtest.sitl.mav import MavResult
from uavtest.sitl.simulator_sih import GRAVITY
from uavtest.sitl.uorb import BatteryStatus

if TYPE_CHECKING:
    from uavtest.sitl.params import ParamStore
    from uavtest.sitl.simulator_sih import Body

__all__ = [
    "INTERVAL_US",
    "WARNING_CRITICAL",
    "WARNING_EMERGENCY",
    "WARNING_LOW",
    "WARNING_NONE",
    "BatterySimulator",
]

INTERVAL_US = 200_000  # 5 Hz
WARNING_NONE, WARNING_LOW, WARNING_CRITICAL, WARNING_EMERGENCY = 0, 1, 2, 3
_RECOGNITION_V = 2.1  # LITHIUM_BATTERY_RECOGNITION_VOLTAGE
_FAILURE_UNIT_SYSTEM_BATTERY = 100
_FAILURE_TYPE_OK, _FAILURE_TYPE_OFF = 0, 1
_FAULT_SPIKES = 1


def _alpha(dt: float, tau: float) -> float:
    """AlphaFilter::setParameters(dt, tau)."""
    return dt / (dt + tau)


_ALPHA_1S = _alpha(INTERVAL_US / 1e6, 1.0)  # the voltage and throttle filters (1 s)


class BatterySimulator:
    """battery_simulator + lib/battery: ``update`` at 5 Hz; ``status`` is the ``battery_status``."""

    __slots__ = (
        "_crit_thr",
        "_drain_us",
        "_emergen_thr",
        "_hover",
        "_initialised",
        "_last_us",
        "_load_drop",
        "_low_thr",
        "_min_pct",
        "_n_cells",
        "_t",
        "_unconnected_us",
        "_v_charged",
        "_v_empty",
        "connected",
        "enabled",
        "force_empty",
        "p",
        "percentage",
        "remaining",
        "throttle_f",
        "voltage",
        "voltage_f",
        "warning",
    )

    def __init__(self, params: ParamStore) -> None:
        self.p = params
        self.percentage = 1.0
        self.force_empty = False
        self.voltage = 0.0
        self.voltage_f = 0.0
        self.throttle_f = 0.0
        self.remaining = 1.0
        self.warning = WARNING_NONE
        self.connected = False
        self._initialised = False
        self._unconnected_us = 0
        self._last_us = 0
        self._t = -1
        self.update_params()

    def update_params(self) -> None:
        """Read the parameters (PX4: on parameter_update), not at every sample."""
        p = self.p
        self.enabled = int(p["SIM_BAT_ENABLE"]) != 0
        self._drain_us = max(p["SIM_BAT_DRAIN"], 1.0) * 1e6
        self._min_pct = p["SIM_BAT_MIN_PCT"] / 100.0
        self._v_empty, self._v_charged = p["BAT1_V_EMPTY"], p["BAT1_V_CHARGED"]
        self._n_cells = int(p["BAT1_N_CELLS"])
        self._load_drop = p["BAT1_V_LOAD_DROP"]
        self._hover = p["MPC_THR_HOVER"]
        self._low_thr, self._crit_thr, self._emergen_thr = (
            p["BAT_LOW_THR"],
            p["BAT_CRIT_THR"],
            p["BAT_EMERGEN_THR"],
        )

    def inject(self, failure_type: int, instance: int) -> MavResult | None:
        """BatterySimulator::updateCommands for FAILURE_UNIT_SYSTEM_BATTERY (None: not handled)."""
        if failure_type not in (_FAILURE_TYPE_OK, _FAILURE_TYPE_OFF):
            return None
        if instance != 0:
            return MavResult.UNSUPPORTED
        self.force_empty = failure_type == _FAILURE_TYPE_OFF
        return MavResult.ACCEPTED

    def update(self, t: int, armed: bool, body: Body) -> None:
        """One sample (BatterySimulator::Run + Battery::updateBatteryStatus); ``status`` builds the topic."""
        if not armed and self._initialised and self.percentage == 1.0 and self.voltage_f == self.voltage:
            self._t = t  # disarmed and settled (full, filter converged, motors off): nothing changes
            if self.throttle_f == 0.0:
                return
        self._t = t
        if armed:
            if self._last_us:
                self.percentage -= (t - self._last_us) / self._drain_us
            self._last_us = t
        else:
            self.percentage = 1.0
            self._last_us = 0
        if self.percentage < self._min_pct:
            self.percentage = self._min_pct
        v_empty, v_charged = self._v_empty, self._v_charged
        n_cells = self._n_cells
        pct = self.percentage
        if self.force_empty or pct <= 0.0:
            cell = v_empty
        else:
            cell = v_empty + (v_charged - v_empty) * (pct if pct < 1.0 else 1.0)
        self.voltage = vbatt = cell * n_cells
        # Battery::updateBatteryStatus
        if not self._initialised:
            self.voltage_f = vbatt
        else:
            self.voltage_f += _ALPHA_1S * (vbatt - self.voltage_f)
        connected = self.voltage_f >= _RECOGNITION_V
        if not connected or self._unconnected_us == 0:
            self._unconnected_us = t
        was_initialised = self._initialised
        self._initialised = connected and t > self._unconnected_us + 2_000_000
        self.connected = connected
        # throttle: collective thrust over hover thrust, times the hover throttle
        throttle = 0.0
        if body.motors:
            fz = GRAVITY - body.az
            throttle = math.sqrt(body.ax * body.ax + body.ay * body.ay + fz * fz) / GRAVITY * self._hover
            if throttle > 1.0:
                throttle = 1.0
        if was_initialised:
            self.throttle_f += _ALPHA_1S * (throttle - self.throttle_f)
        else:
            self.throttle_f = throttle
        soc = -1.0
        if n_cells > 0:
            cell_v = self.voltage_f / n_cells + self.throttle_f * self._load_drop
            soc = (cell_v - v_empty) / (v_charged - v_empty) if v_charged > v_empty else 0.0
            soc = 0.0 if soc < 0.0 else 1.0 if soc > 1.0 else soc
        self.remaining = soc
        if connected and self._initialised:
            if soc < self._emergen_thr:
                self.warning = WARNING_EMERGENCY
            elif soc < self._crit_thr:
                self.warning = WARNING_CRITICAL
            elif soc < self._low_thr:
                self.warning = WARNING_LOW
            else:
                self.warning = WARNING_NONE

    @property
    def status(self) -> BatteryStatus | None:
        """battery_status of the last sample (None before the first): built when read."""
        if self._t < 0:
            return None
        v_empty, v_charged, n_cells, soc = self._v_empty, self._v_charged, self._n_cells, self.remaining
        faults = 0
        if n_cells > 0 and self.voltage > n_cells * v_charged * 1.05:
            faults |= 1 << _FAULT_SPIKES
        # Battery::computeScale (on the voltage-based charge)
        bat_v = v_empty + (v_charged - v_empty) * soc
        scale = v_charged / bat_v if bat_v > 0 else 1.0
        scale = 1.3 if scale > 1.3 else 1.0 if not scale >= 1.0 else scale
        return BatteryStatus(
            self._t, self.connected, self.voltage, self.voltage_f, -1.0, -1.0, 0.0, 0.0, soc, scale,
            math.nan, math.nan, n_cells, 0, 0, 0, 1, faults, self.warning,
        )  # fmt: skip
