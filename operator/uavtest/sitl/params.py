"""PX4 parameters: the defaults that govern the simulated vehicle, and the parameter store.

Defaults and types are PX4 v1.15 SITL's (``sihsim_quadx``) as its logs show them, e.g.
``NAV_ACC_RAD`` 2.0 (the airframe's value; the PX4-wide default is 10). Unknown names are
stored and echoed like PX4 does for any parameter it has. PX4 sends INT32 values packed
byte-wise into PARAM_VALUE's float field (``MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE``).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterator, Mapping

from uavtest.sitl.mav import ParamType

__all__ = ["DEFAULTS", "ParamStore", "decode_param_value", "encode_param_value"]

I, F = ParamType.INT32, ParamType.REAL32

#: name → (type, default)
DEFAULTS: dict[str, tuple[ParamType, float]] = {
    # commander
    "COM_DISARM_LAND": (F, 2.0),
    "COM_DISARM_PRFLT": (F, 10.0),
    "COM_SPOOLUP_TIME": (F, 1.0),
    "COM_DL_LOSS_T": (I, 10),
    "COM_RC_LOSS_T": (F, 0.5),
    "COM_RC_IN_MODE": (I, 1),
    "COM_ARM_WO_GPS": (I, 1),
    "COM_HOME_EN": (I, 1),
    "COM_OBL_RC_ACT": (I, 0),
    "COM_FLTMODE1": (I, -1),
    "COM_LOW_BAT_ACT": (I, 2),
    # navigator / mission
    "NAV_ACC_RAD": (F, 2.0),
    "NAV_MC_ALT_RAD": (F, 0.8),
    "NAV_DLL_ACT": (I, 0),
    "NAV_RCL_ACT": (I, 2),
    "NAV_LOITER_RAD": (F, 80.0),
    "NAV_TRAFF_AVOID": (I, 1),
    "MIS_TAKEOFF_ALT": (F, 2.5),
    "MIS_YAW_ERR": (F, 12.0),
    "MIS_YAW_TMT": (F, -1.0),
    "MIS_DIST_1WP": (F, 900.0),
    "RTL_RETURN_ALT": (F, 30.0),
    "RTL_DESCEND_ALT": (F, 10.0),
    "RTL_LAND_DELAY": (F, 0.0),
    "RTL_MIN_DIST": (F, 10.0),
    "RTL_TYPE": (I, 0),
    "GF_ACTION": (I, 2),
    "GF_MAX_HOR_DIST": (F, 0.0),
    "GF_MAX_VER_DIST": (F, 0.0),
    # multicopter position control
    "MPC_YAW_MODE": (I, 0),
    "MPC_XY_CRUISE": (F, 5.0),
    "MPC_XY_VEL_MAX": (F, 12.0),
    "MPC_VEL_MANUAL": (F, 10.0),
    "MPC_ACC_HOR": (F, 3.0),
    "MPC_ACC_HOR_MAX": (F, 5.0),
    "MPC_JERK_AUTO": (F, 4.0),
    "MPC_Z_V_AUTO_UP": (F, 3.0),
    "MPC_Z_V_AUTO_DN": (F, 1.5),
    "MPC_Z_VEL_MAX_UP": (F, 3.0),
    "MPC_Z_VEL_MAX_DN": (F, 1.5),
    "MPC_TKO_SPEED": (F, 1.5),
    "MPC_TKO_RAMP_T": (F, 3.0),
    "MPC_LAND_SPEED": (F, 0.7),
    "MPC_LAND_ALT1": (F, 10.0),
    "MPC_LAND_ALT2": (F, 5.0),
    "MPC_LAND_ALT3": (F, 1.0),
    "MPC_LAND_CRWL": (F, 0.3),
    "MPC_TILTMAX_AIR": (F, 45.0),
    "MPC_TILTMAX_LND": (F, 12.0),
    "MPC_MAN_TILT_MAX": (F, 35.0),
    "MPC_MAN_Y_MAX": (F, 150.0),
    "MPC_XY_P": (F, 0.95),
    "MPC_Z_P": (F, 1.0),
    "MPC_XY_VEL_P_ACC": (F, 1.8),
    "MPC_XY_VEL_I_ACC": (F, 0.4),
    "MPC_XY_VEL_D_ACC": (F, 0.2),
    "MPC_Z_VEL_P_ACC": (F, 4.0),
    "MPC_Z_VEL_I_ACC": (F, 2.0),
    "MPC_ACC_UP_MAX": (F, 4.0),
    "MPC_ACC_DOWN_MAX": (F, 3.0),
    "MPC_YAWRAUTO_MAX": (F, 45.0),
    "MPC_YAWRAUTO_ACC": (F, 60.0),
    "MPC_THR_HOVER": (F, 0.5),
    "MPC_XY_ERR_MAX": (F, 2.0),
    "MPC_XY_TRAJ_P": (F, 0.5),
    "MPC_HOLD_DZ": (F, 0.1),
    "MPC_POS_MODE": (I, 4),
    "MPC_ALT_MODE": (I, 2),
    "MC_YAWRATE_MAX": (F, 200.0),
    # land detector
    "LNDMC_TRIG_TIME": (F, 1.0),
    "LNDMC_Z_VEL_MAX": (F, 0.25),
    "LNDMC_XY_VEL_MAX": (F, 1.5),
    # system
    "MAV_SYS_ID": (I, 1),
    "MAV_COMP_ID": (I, 1),
    "MAV_TYPE": (I, 2),
    "SYS_AUTOSTART": (I, 10040),
    "SDLOG_MODE": (I, 0),
    "SDLOG_PROFILE": (I, 1),
    "EKF2_HGT_REF": (I, 1),
    "BAT1_N_CELLS": (I, 4),
}


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
        for name, value in (overrides or {}).items():
            self.set(name, value)

    def __contains__(self, name: str) -> bool:
        return name in self._values

    def __len__(self) -> int:
        return len(self._values)

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __getitem__(self, name: str) -> float:
        return self._values[name]

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
            if ptype is None:
                ptype = ParamType.INT32 if isinstance(value, int) else ParamType.REAL32
            self._types[name] = ParamType.INT32 if int(ptype) == ParamType.INT32 else ParamType.REAL32
        if self._types[name] == ParamType.INT32:
            if isinstance(value, float) and not math.isfinite(value):
                value = 0
            stored: float = int(round(value))
        else:
            stored = _f32(float(value))
        self._values[name] = stored
        return stored

    def items(self) -> list[tuple[str, ParamType, float]]:
        return [(n, self._types[n], v) for n, v in self._values.items()]
