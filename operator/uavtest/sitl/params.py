"""PX4 parameters: the defaults that govern the simulated vehicle, and the parameter store.

Defaults and types are PX4 v1.15 SITL's (``sihsim_quadx``) as its logs show them, e.g.
``NAV_ACC_RAD`` 2.0 (the airframe's value; the PX4-wide default is 10); a unit test checks them
against the SIH logs. ``DEFAULTS`` is also the list of what the vehicle *models*. Other PX4 v1.15
parameters (``uavtest.px4.parameters``) are stored and echoed like PX4 does, without effect;
names PX4 v1.15 does not have are refused (``known`` is False). PX4 sends INT32 values packed
byte-wise into PARAM_VALUE's float field (``MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE``).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterator, Mapping

from uavtest.px4 import parameters as px4_parameters
from uavtest.sitl.mav import ParamType

__all__ = [
    "DEFAULTS",
    "READ_WHEN_USED",
    "UNMODELLED_AT_BOOT",
    "ParamStore",
    "decode_param_value",
    "encode_param_value",
]

INT, FLOAT = ParamType.INT32, ParamType.REAL32

#: name → (type, default): the parameters the simulated vehicle *models* (some code here reads
#: each; a unit test checks that both ways against the sitl sources, and the values against the
#: PX4 v1.15 SIH logs). Every other PX4 v1.15 parameter is stored and echoed without effect.
DEFAULTS: dict[str, tuple[ParamType, float]] = {
    # commander
    "COM_DISARM_LAND": (FLOAT, 2.0),
    "COM_DISARM_PRFLT": (FLOAT, 10.0),
    "COM_SPOOLUP_TIME": (FLOAT, 1.0),
    "COM_OBS_AVOID": (INT, 0),
    "COM_DL_LOSS_T": (INT, 10),
    "COM_RC_LOSS_T": (FLOAT, 0.5),
    "COM_OF_LOSS_T": (FLOAT, 1.0),
    "COM_OBL_RC_ACT": (INT, 0),
    "COM_FAIL_ACT_T": (FLOAT, 5.0),
    "COM_RC_IN_MODE": (INT, 1),
    "COM_RCL_EXCEPT": (INT, 0),
    "COM_RC_OVERRIDE": (INT, 1),
    "COM_RC_STICK_OV": (FLOAT, 30.0),
    "COM_LOW_BAT_ACT": (INT, 2),
    "COM_POS_FS_DELAY": (INT, 1),
    "COM_POSCTL_NAVL": (INT, 0),
    "COM_ARM_MIS_REQ": (INT, 0),
    "COM_LKDOWN_TKO": (FLOAT, 3.0),
    "COM_ACT_FAIL_ACT": (INT, 0),
    "CBRK_FLIGHTTERM": (INT, 121212),
    # failure detector / failure injection
    "FD_FAIL_R": (INT, 60),
    "FD_FAIL_R_TTRI": (FLOAT, 0.3),
    "FD_ACT_EN": (INT, 1),
    "SYS_FAILURE_EN": (INT, 1),
    # battery (battery_simulator + lib/battery)
    "SIM_BAT_ENABLE": (INT, 1),
    "SIM_BAT_DRAIN": (FLOAT, 60.0),
    "SIM_BAT_MIN_PCT": (FLOAT, 50.0),
    "BAT1_N_CELLS": (INT, 4),
    "BAT1_V_CHARGED": (FLOAT, 4.05),
    "BAT1_V_EMPTY": (FLOAT, 3.6),
    "BAT1_V_LOAD_DROP": (FLOAT, 0.1),
    "BAT_LOW_THR": (FLOAT, 0.15),
    "BAT_CRIT_THR": (FLOAT, 0.07),
    "BAT_EMERGEN_THR": (FLOAT, 0.05),
    # estimator
    "EKF2_NOAID_TOUT": (INT, 5000000),
    # navigator / mission
    "NAV_ACC_RAD": (FLOAT, 2.0),
    "NAV_MC_ALT_RAD": (FLOAT, 0.8),
    "NAV_DLL_ACT": (INT, 0),
    "NAV_RCL_ACT": (INT, 2),
    "MIS_TAKEOFF_ALT": (FLOAT, 2.5),
    "MIS_YAW_ERR": (FLOAT, 12.0),
    "MIS_YAW_TMT": (FLOAT, -1.0),
    "MIS_DIST_1WP": (FLOAT, 900.0),  # navigator/mission_feasibility.py
    "NAV_LOITER_RAD": (FLOAT, 80.0),  # Loiter::set_loiter_position's "already on the loiter"
    "RTL_RETURN_ALT": (FLOAT, 30.0),
    "RTL_DESCEND_ALT": (FLOAT, 10.0),
    "RTL_LAND_DELAY": (FLOAT, 0.0),
    "RTL_MIN_DIST": (FLOAT, 10.0),
    "RTL_TYPE": (INT, 0),
    "RTL_CONE_ANG": (INT, 45),
    # geofence
    "GF_ACTION": (INT, 2),
    "GF_MAX_HOR_DIST": (FLOAT, 0.0),
    "GF_MAX_VER_DIST": (FLOAT, 0.0),
    # multicopter position control
    "MPC_YAW_MODE": (INT, 0),
    "MPC_XY_CRUISE": (FLOAT, 5.0),
    "MPC_XY_VEL_MAX": (FLOAT, 12.0),
    "MPC_VEL_MANUAL": (FLOAT, 10.0),
    "MPC_ACC_HOR": (FLOAT, 3.0),
    "MPC_JERK_AUTO": (FLOAT, 4.0),
    "MPC_Z_V_AUTO_UP": (FLOAT, 3.0),
    "MPC_Z_V_AUTO_DN": (FLOAT, 1.5),
    "MPC_Z_VEL_MAX_UP": (FLOAT, 3.0),
    "MPC_Z_VEL_MAX_DN": (FLOAT, 1.5),
    "MPC_TKO_SPEED": (FLOAT, 1.5),
    "MPC_TKO_RAMP_T": (FLOAT, 3.0),
    "MPC_LAND_SPEED": (FLOAT, 0.7),
    "MPC_LAND_ALT1": (FLOAT, 10.0),
    "MPC_LAND_ALT2": (FLOAT, 5.0),
    "MPC_LAND_ALT3": (FLOAT, 1.0),
    "MPC_LAND_CRWL": (FLOAT, 0.3),
    "MPC_TILTMAX_AIR": (FLOAT, 45.0),
    "MPC_MAN_TILT_MAX": (FLOAT, 35.0),
    "MPC_MAN_Y_MAX": (FLOAT, 150.0),
    "MPC_MAN_Y_TAU": (FLOAT, 0.08),
    "MPC_XY_P": (FLOAT, 0.95),
    "MPC_Z_P": (FLOAT, 1.0),
    "MPC_XY_VEL_P_ACC": (FLOAT, 1.8),
    "MPC_XY_VEL_I_ACC": (FLOAT, 0.4),
    "MPC_XY_VEL_D_ACC": (FLOAT, 0.2),
    "MPC_XY_TRAJ_P": (FLOAT, 0.5),
    "MPC_VELD_LP": (FLOAT, 5.0),
    "MPC_Z_VEL_P_ACC": (FLOAT, 4.0),
    "MPC_Z_VEL_I_ACC": (FLOAT, 2.0),
    "MPC_ACC_UP_MAX": (FLOAT, 4.0),
    "MPC_ACC_DOWN_MAX": (FLOAT, 3.0),
    "MPC_YAWRAUTO_MAX": (FLOAT, 45.0),
    "MPC_YAWRAUTO_ACC": (FLOAT, 60.0),
    "MPC_XY_ERR_MAX": (FLOAT, 2.0),
    "MPC_HOLD_DZ": (FLOAT, 0.1),
    "MPC_XY_MAN_EXPO": (FLOAT, 0.6),
    "MPC_Z_MAN_EXPO": (FLOAT, 0.6),
    "MPC_YAW_EXPO": (FLOAT, 0.6),
    "MPC_VEL_MAN_SIDE": (FLOAT, -1.0),
    "MPC_VEL_MAN_BACK": (FLOAT, -1.0),
    "MC_ORBIT_RAD_MAX": (FLOAT, 1000.0),
    "MPC_THR_HOVER": (FLOAT, 0.5),
    "MPC_USE_HTE": (INT, 1),
    # attitude and rate control, the yaw axis (mc_att_control, mc_rate_control)
    "MC_YAW_P": (FLOAT, 2.8),
    "MC_YAW_WEIGHT": (FLOAT, 0.4),
    "MC_YAWRATE_MAX": (FLOAT, 200.0),
    "MC_YAWRATE_P": (FLOAT, 0.2),
    "MC_YAWRATE_I": (FLOAT, 0.1),
    "MC_YAWRATE_K": (FLOAT, 1.0),
    "MC_YR_INT_LIM": (FLOAT, 0.3),
    # hover thrust estimator (mc_hover_thrust_estimator)
    "HTE_HT_NOISE": (FLOAT, 0.0036),
    "HTE_ACC_GATE": (FLOAT, 3.0),
    "HTE_HT_ERR_INIT": (FLOAT, 0.1),
    "HTE_VXY_THR": (FLOAT, 10.0),
    "HTE_VZ_THR": (FLOAT, 2.0),
    "MPC_POS_MODE": (INT, 4),
    "MPC_HOLD_MAX_XY": (FLOAT, 0.8),
    "MPC_JERK_MAX": (FLOAT, 8.0),
    # collision prevention (lib/collision_prevention)
    "CP_DIST": (FLOAT, -1.0),
    "CP_DELAY": (FLOAT, 0.4),
    "CP_GUIDE_ANG": (FLOAT, 30.0),
    "CP_GO_NO_DATA": (INT, 0),
    # land detector
    "LNDMC_TRIG_TIME": (FLOAT, 1.0),
    "LNDMC_Z_VEL_MAX": (FLOAT, 0.25),
    "LNDMC_XY_VEL_MAX": (FLOAT, 1.5),
}


#: PX4 v1.15 SIH parameters held from boot (listed by PARAM_REQUEST_LIST, logged in the ULog's
#: parameter section) that have no effect in the simulator; values from the PX4 table (SIH value).
UNMODELLED_AT_BOOT: tuple[str, ...] = (
    "COM_ARM_WO_GPS",
    "COM_HOME_EN",
    "COM_FLTMODE1",
    "NAV_TRAFF_AVOID",
    "MPC_ACC_HOR_MAX",
    "MPC_TILTMAX_LND",
    "MPC_ALT_MODE",
    "MAV_SYS_ID",
    "MAV_COMP_ID",
    "MAV_TYPE",
    "SYS_AUTOSTART",
    "SDLOG_MODE",
    "SDLOG_PROFILE",
    "EKF2_HGT_REF",
)


#: PX4 v1.15 parameters the simulator reads that PX4 SIH does not hold at boot: PX4 lists (and logs)
#: a parameter once a module has looked it up, and these are looked up only when needed
#: (FeasibilityChecker reads MIS_TKO_LAND_REQ at its first mission check). ``ParamStore`` stores
#: each with PX4's default when it is first read, so it is listed from then on, as on PX4.
READ_WHEN_USED: tuple[str, ...] = ("MIS_TKO_LAND_REQ",)


def encode_param_value(value: float, ptype: ParamType) -> float:
    """PARAM_VALUE.param_value: a float, or an INT32's four bytes read as a float (PX4)."""
    if ptype == ParamType.INT32:
        return struct.unpack("<f", struct.pack("<i", int(value)))[0]
    return float(value)


def decode_param_value(raw: float, ptype: int) -> int | float:
    """The value a PARAM_SET carries: INT32 unpacked byte-wise, anything else as a float."""
    if ptype == ParamType.INT32:
        return struct.unpack("<i", struct.pack("<f", raw))[0]
    return float(raw)


def _f32(value: float) -> float:
    """Round to single precision, as PX4 stores a float parameter."""
    return struct.unpack("<f", struct.pack("<f", value))[0]


class ParamStore:
    """Typed PX4 parameters in a stable order (PARAM_VALUE index = position)."""

    def __init__(self, overrides: Mapping[str, int | float] | None = None) -> None:
        self._types: dict[str, ParamType] = {}
        self._values: dict[str, float] = {}
        for name, (ptype, default) in DEFAULTS.items():
            self._types[name] = ptype
            self._values[name] = int(default) if ptype == ParamType.INT32 else _f32(default)
        for name in UNMODELLED_AT_BOOT:
            self.ensure(name)
        for name, value in (overrides or {}).items():
            self.set(name, value)

    def __contains__(self, name: str) -> bool:
        return name in self._values

    def __len__(self) -> int:
        return len(self._values)

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __getitem__(self, name: str) -> float:
        """The value of ``name``; a PX4 v1.15 parameter not stored yet is stored first (else KeyError)."""
        if name not in self._values and not self.ensure(name):
            raise KeyError(name)
        return self._values[name]

    def known(self, name: str) -> bool:
        """Whether the vehicle has ``name``: stored, or a parameter PX4 v1.15 defines."""
        return name in self._values or px4_parameters.known(name)

    def ensure(self, name: str) -> bool:
        """Store a PX4 v1.15 parameter not stored yet with its SIH value (or PX4 default)."""
        if name in self._values:
            return True
        p = px4_parameters.lookup(name)
        if p is None:
            return False
        self.set(name, p.vehicle_default, ParamType.INT32 if p.is_int else ParamType.REAL32)
        return True

    def type_of(self, name: str) -> ParamType:
        return self._types[name]

    def index_of(self, name: str) -> int:
        return list(self._values).index(name)

    def name_at(self, index: int) -> str | None:
        names = list(self._values)
        return names[index] if 0 <= index < len(names) else None

    def set(self, name: str, value: int | float, ptype: ParamType | int | None = None) -> float:
        """Store a value (a new name takes ``ptype``, or INT32 for Python ints); returns what is stored."""
        if name not in self._types:
            p = px4_parameters.lookup(name)
            if p is not None:  # PX4 keeps its own type whatever the sender says
                ptype = ParamType.INT32 if p.is_int else ParamType.REAL32
            elif ptype is None:
                ptype = ParamType.INT32 if isinstance(value, int) else ParamType.REAL32
            self._types[name] = ParamType.INT32 if int(ptype) == ParamType.INT32 else ParamType.REAL32
        if self._types[name] == ParamType.INT32:
            if isinstance(value, float) and not math.isfinite(value):
                value = 0
            stored: float = round(value)
        else:
            stored = _f32(float(value))
        self._values[name] = stored
        return stored

    def items(self) -> list[tuple[str, ParamType, float]]:
        return [(n, self._types[n], v) for n, v in self._values.items()]
