"""Offboard setpoints: SET_POSITION_TARGET_* → ``offboard_control_mode`` + ``trajectory_setpoint``.

Follows PX4 v1.15 ``src/modules/mavlink/mavlink_receiver.cpp``
(``handle_message_set_position_target_local_ned`` / ``_global_int``):

- LOCAL_NED: position, velocity (acceleration) per ``type_mask``; BODY_NED: velocity rotated by
  the vehicle's yaw, no position; any other frame (LOCAL_OFFSET_NED, BODY_OFFSET_NED, …) is
  refused with PX4's STATUSTEXT ``SET_POSITION_TARGET_LOCAL_NED coordinate frame N unsupported``.
- GLOBAL_INT (AMSL), GLOBAL_RELATIVE_ALT_INT (PX4's formula ``home.alt - alt - ref_alt``) and
  GLOBAL_TERRAIN_ALT_INT (flat ground: terrain at home altitude) → local position.
- ``offboard_control_mode`` is published for every valid setpoint (the offboard *signal*,
  ``HealthAndArmingChecks/checks/offboardCheck.cpp``: present while the last one is younger
  than ``COM_OF_LOSS_T``); the ``trajectory_setpoint`` only while the nav state is OFFBOARD.

Not modelled (said, never ignored): acceleration setpoints (``Offboard: acceleration setpoints
not modelled``), and SET_ATTITUDE_TARGET (attitude / body-rate offboard).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from uavtest.mavlink_numbers import MavFrame
from uavtest.px4.modes import NavState
from uavtest.sitl import mav
from uavtest.sitl.mav import MavSeverity, Msg
from uavtest.sitl.mc_pos_control import Goal, GoalKind
from uavtest.sitl.uorb import OffboardControlMode

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import Vehicle

__all__ = ["Offboard"]

FRAME_GLOBAL_INT = int(MavFrame.GLOBAL_INT)
FRAME_GLOBAL_RELATIVE_ALT_INT = int(MavFrame.GLOBAL_RELATIVE_ALT_INT)
FRAME_LOCAL_NED = int(MavFrame.LOCAL_NED)
FRAME_BODY_NED = int(MavFrame.BODY_NED)
FRAME_GLOBAL_TERRAIN_ALT_INT = int(MavFrame.GLOBAL_TERRAIN_ALT_INT)
# POSITION_TARGET_TYPEMASK
X_IGNORE, Y_IGNORE, Z_IGNORE = 1, 2, 4
VX_IGNORE, VY_IGNORE, VZ_IGNORE = 8, 16, 32
AX_IGNORE, AY_IGNORE, AZ_IGNORE = 64, 128, 256
FORCE_SET = 512
YAW_IGNORE, YAW_RATE_IGNORE = 1024, 2048
_ACC_IGNORE = AX_IGNORE | AY_IGNORE | AZ_IGNORE
_NAN = math.nan
OCM_LOG_US = 100_000  # PX4's logger: offboard_control_mode at 100 ms (logged_topics.cpp)


def _m(mask: int, bit: int, value: object) -> float:
    return _NAN if mask & bit else float(value)  # type: ignore[arg-type]


def _valid(pos: tuple[float, float, float], vel: tuple[float, float, float]) -> bool:
    """PositionControl::_inputValid: every axis has a position or a velocity, x and y in pairs.

    An invalid setpoint is not refused: MulticopterPositionControl flies its failsafe setpoint
    instead (zero velocity: "Failsafe: stop and wait", a console warning only).
    """
    for i in range(3):
        if pos[i] != pos[i] and vel[i] != vel[i]:
            return False
    return (pos[0] == pos[0]) == (pos[1] == pos[1]) and (vel[0] == vel[0]) == (vel[1] == vel[1])


class Offboard:
    """The offboard signal and the last setpoint, for the commander and position control."""

    def __init__(self, v: Vehicle) -> None:
        self.v = v
        self.last_us: int | None = None  # offboard_control_mode.timestamp
        self.goal = Goal(GoalKind.OFFBOARD)
        self._logged_us = -OCM_LOG_US
        self._told_unmodelled: set[str] = set()

    def signal(self, t: int) -> bool:
        """PX4's ``not offboard_control_signal_lost``: a setpoint within COM_OF_LOSS_T."""
        last = self.last_us
        return last is not None and t < last + self.v.params["COM_OF_LOSS_T"] * 1e6

    def enter(self) -> None:
        """Entering OFFBOARD: hold where the vehicle is until the next setpoint (PX4 publishes
        trajectory_setpoint only in OFFBOARD, so the previous one is the hold position)."""
        st = self.v.st
        self.goal = Goal(GoalKind.OFFBOARD, st.x, st.y, st.z, st.yaw)

    def want_takeoff(self, z: float) -> bool:
        """MulticopterPositionControl: armed on the ground, a setpoint above or climbing."""
        g = self.goal
        return (g.z == g.z and g.z < z) or (g.vel[2] == g.vel[2] and g.vel[2] < 0.0)

    def _unmodelled(self, what: str) -> None:
        if what not in self._told_unmodelled:
            self._told_unmodelled.add(what)
            self.v.text(MavSeverity.WARNING, f"Offboard: {what} not modelled")

    def _publish(
        self, mask: int, pos: tuple[float, float, float], vel: tuple[float, float, float], name: str
    ) -> None:
        v = self.v
        f_acc = (mask & _ACC_IGNORE) != _ACC_IGNORE
        if f_acc and mask & FORCE_SET:
            v.text(MavSeverity.CRITICAL, f"{name} force not supported")
            return
        has_pos = not all(c != c for c in pos)
        has_vel = not all(c != c for c in vel)
        if f_acc:
            self._unmodelled("acceleration setpoints")
            if not (has_pos or has_vel):
                return
        if not (has_pos or has_vel):
            v.text(MavSeverity.CRITICAL, f"{name} invalid")
            return
        t = v.time_us
        self.last_us = t
        if t - self._logged_us >= OCM_LOG_US:
            self._logged_us = t
            v.recorder.data(OffboardControlMode(t, has_pos, has_vel, False, False, False, False, False))
        if v.commander.nav_state == NavState.OFFBOARD:
            yaw = _m(mask, YAW_IGNORE, self._yaw)
            yawspeed = _m(mask, YAW_RATE_IGNORE, self._yawspeed)
            if not _valid(pos, vel):  # PX4 flies generateFailsafeSetpoint: stop and wait
                pos, vel = (_NAN, _NAN, _NAN), (0.0, 0.0, 0.0)
            self.goal = Goal(GoalKind.OFFBOARD, pos[0], pos[1], pos[2], yaw, vel=vel, yawspeed=yawspeed)

    def local_ned(self, msg: Msg) -> list[Msg]:
        f = msg.fields
        if not self._for_us(f):
            return []
        mask = int(f.get("type_mask", 0))
        frame = int(f.get("coordinate_frame", FRAME_LOCAL_NED))
        name = "SET_POSITION_TARGET_LOCAL_NED"
        vx, vy, vz = (f.get(k, 0.0) for k in ("vx", "vy", "vz"))
        if frame == FRAME_LOCAL_NED:
            pos = (_m(mask, X_IGNORE, f.get("x", 0.0)), _m(mask, Y_IGNORE, f.get("y", 0.0)),
                   _m(mask, Z_IGNORE, f.get("z", 0.0)))  # fmt: skip
            vel = (_m(mask, VX_IGNORE, vx), _m(mask, VY_IGNORE, vy), _m(mask, VZ_IGNORE, vz))
        elif frame == FRAME_BODY_NED:
            pos = (_NAN, _NAN, _NAN)
            if mask & (VX_IGNORE | VY_IGNORE | VZ_IGNORE):  # PX4: any ignored → no velocity
                vel = (_NAN, _NAN, _NAN)
            else:
                yaw = self.v.st.yaw
                c, s = math.cos(yaw), math.sin(yaw)
                bx, by = float(vx), float(vy)
                vel = (c * bx - s * by, s * bx + c * by, float(vz))
        else:
            self.v.text(MavSeverity.CRITICAL, f"{name} coordinate frame {frame} unsupported")
            return []
        self._yaw, self._yawspeed = f.get("yaw", 0.0), f.get("yaw_rate", 0.0)
        self._publish(mask, pos, vel, name)
        return []

    def global_int(self, msg: Msg) -> list[Msg]:
        f = msg.fields
        if not self._for_us(f):
            return []
        v = self.v
        mask = int(f.get("type_mask", 0))
        name = "SET_POSITION_TARGET_GLOBAL_INT"
        if not mask & (X_IGNORE | Y_IGNORE | Z_IGNORE):
            frame = int(f.get("coordinate_frame", FRAME_GLOBAL_INT))
            x, y = v.proj.project(int(f.get("lat_int", 0)) / 1e7, int(f.get("lon_int", 0)) / 1e7)
            alt = float(f.get("alt", 0.0))
            ref_alt = v.home_alt  # vehicle_local_position.ref_alt
            if frame == FRAME_GLOBAL_INT:
                z = ref_alt - alt
            elif frame == FRAME_GLOBAL_RELATIVE_ALT_INT:
                if not v.commander.home_set:
                    return []  # PX4: home altitude required
                z = v.commander.home[5] - alt - ref_alt
            elif frame == FRAME_GLOBAL_TERRAIN_ALT_INT:
                z = ref_alt - (alt + v.home_alt)  # terrain: the flat ground at home altitude
            else:
                v.text(MavSeverity.CRITICAL, f"{name} invalid coordinate frame {frame}")
                return []
            pos = (x, y, z)
        else:
            pos = (_NAN, _NAN, _NAN)
        vel = tuple(
            _m(mask, bit, f.get(k, 0.0))
            for bit, k in ((VX_IGNORE, "vx"), (VY_IGNORE, "vy"), (VZ_IGNORE, "vz"))
        )
        self._yaw, self._yawspeed = f.get("yaw", 0.0), f.get("yaw_rate", 0.0)
        self._publish(mask, pos, vel, name)  # type: ignore[arg-type]
        return []

    def attitude_target(self, msg: Msg) -> list[Msg]:
        if self._for_us(msg.fields):
            self._unmodelled("SET_ATTITUDE_TARGET")
        return []

    @staticmethod
    def _for_us(f: dict) -> bool:  # type: ignore[type-arg]
        return int(f.get("target_system", 0)) in (0, mav.SYSTEM_ID) and int(f.get("target_component", 0)) in (
            0,
            mav.COMPONENT_ID,
        )

    _yaw: object = 0.0
    _yawspeed: object = 0.0
