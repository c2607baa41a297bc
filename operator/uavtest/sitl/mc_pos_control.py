"""PX4-like multicopter position control: trajectory generation, position/velocity loops, yaw.

What gives PX4 its flight times, modelled after PX4 v1.15's ``mc_pos_control`` and
``FlightTaskAuto``/``PositionSmoothing``:

- a reference point runs towards the target at up to the cruise speed (``MPC_XY_CRUISE`` or a
  DO_CHANGE_SPEED override), accelerating at most ``MPC_ACC_HOR`` with jerk ``MPC_JERK_AUTO``
  and slowing so that it stops at the target;
- the reference is *time-stretched* when the vehicle lags behind it (PX4's ``MPC_XY_ERR_MAX``):
  its clock runs at ``1 - error / MPC_XY_ERR_MAX``, which is why PX4 cruises at 3.7-4.4 m/s
  with MPC_XY_CRUISE 5;
- position P (``MPC_XY_P``, ``MPC_Z_P``) and velocity PI (``MPC_*_VEL_P_ACC``, ``_I_ACC``)
  loops turn the reference into an acceleration command, limited by the tilt ``MPC_TILTMAX_AIR``;
- vertical speeds ``MPC_Z_V_AUTO_UP/DN``, takeoff ``MPC_TKO_SPEED`` after a ``MPC_TKO_RAMP_T``
  ramp, landing ``MPC_LAND_SPEED`` below ``MPC_LAND_ALT2`` (interpolated up to ``MPC_LAND_ALT1``)
  and ``MPC_LAND_CRWL`` below ``MPC_LAND_ALT3`` (PX4 SIH has a range finder), the descent
  tracking the integrated altitude of that speed profile as PX4's PositionSmoothing does;
- the heading ``MPC_YAW_MODE`` picks (``FlightTaskAuto::_set_heading_from_mode``): 0 towards
  the target, 1 towards home, 2 away from home (each only from outside the acceptance radius,
  held inside it), 3 along the trajectory (``_generateHeadingAlongTraj``: its velocity, while
  faster than 0.1 m/s and more than 2 m from the target), 4 as 0 with the trajectory held still
  until the heading setpoint is within ``MIS_YAW_ERR`` of it; the setpoint turns at
  ``MPC_YAWRAUTO_MAX`` at most.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

from uavtest.sitl import velocity_smoothing
from uavtest.sitl.mc_att_control import YawGains, yaw_rate_setpoint
from uavtest.sitl.params import ParamStore
from uavtest.sitl.simulator_sih import GRAVITY
from uavtest.sitl.stick_acceleration_xy import StickAccelerationXY
from uavtest.sitl.sticks import expo_deadzone, limit_unit_length

__all__ = ["IDLE", "Controller", "Goal", "GoalKind", "Limits", "wrap_pi"]

#: m/s (down): where FlightTaskAuto's takeoff trajectory starts its climb-rate ramp (PX4 v1.15 SIH
#: logs: trajectory_setpoint.vz +0.70 at arming, rising to -MPC_TKO_SPEED at MPC_TKO_SPEED /
#: MPC_TKO_RAMP_T)
TKO_RAMP_START = 0.7
#: FlightTaskAuto::_generateHeadingAlongTraj (MPC_YAW_MODE 3): the trajectory's horizontal speed
#: (m/s) above which, and the distance to the target (m) beyond which, the heading follows it
ALONG_TRAJ_SPEED = 0.1
ALONG_TRAJ_DIST = 2.0
YAWSPEED_FILTER_TAU = 0.2  # s: FlightTaskAuto's _yawspeed_filter
#: the downward acceleration (net of gravity) at the least thrust in flight: MPC_THR_MIN 0.12 at a
#: hover thrust of 0.5 gives 0.76 g
AZ_MIN_THRUST = 0.8 * GRAVITY
#: the Gazebo system's vertical integrator, a tenth of MPC_Z_VEL_I_ACC: its local planner's flights
#: were calibrated with it (``Controller.px4_vertical`` False)
Z_I_SCALE = 0.1


def wrap_pi(a: float) -> float:
    while a > math.pi:
        a -= 2 * math.pi
    while a < -math.pi:
        a += 2 * math.pi
    return a


class GoalKind(Enum):
    IDLE = "idle"  # on the ground, motors at idle (armed) or off
    TAKEOFF = "takeoff"  # climb to z above x, y
    POSITION = "position"  # fly to x, y, z
    LAND = "land"  # descend above x, y until on the ground
    VELOCITY = "velocity"  # position mode sticks: body velocity, climb rate, yaw rate
    ALTITUDE = "altitude"  # altitude mode sticks: tilt, climb rate, yaw rate
    ATTITUDE = "attitude"  # manual/stabilized sticks: tilt, thrust, yaw rate
    OFFBOARD = "offboard"  # trajectory_setpoint of an offboard client: x, y, z and/or vel, yaw / yawspeed


NO_TRACK = (math.nan, math.nan, math.nan)
NO_NEXT = (math.nan, math.nan, math.nan)


@dataclass(slots=True)
class Goal:
    kind: GoalKind = GoalKind.IDLE
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw: float = math.nan  # nan: face the direction of travel (MPC_YAW_MODE 0), else hold
    speed: float = math.nan  # nan: MPC_XY_CRUISE
    sticks: tuple[float, float, float, float] = (0.0, 0.0, 0.5, 0.0)  # x fwd, y right, z thrust 0..1, r yaw
    vel: tuple[float, float, float] = (math.nan, math.nan, math.nan)  # offboard velocity (nan: not set)
    yawspeed: float = math.nan  # offboard yaw rate (nan: not set)
    #: POSITION: the previous waypoint (position_setpoint_triplet.previous: x, y, z), the start
    #: of the track to x, y, z; NO_TRACK: none (fly straight to x, y)
    prev: tuple[float, float, float] = NO_TRACK
    acc_rad: float = math.nan  # POSITION: the target's acceptance radius (nan: NAV_ACC_RAD)
    #: POSITION: position_setpoint_triplet.next (x, y, z), the waypoint after the target that the
    #: trajectory turns towards without stopping; NaN: none (stop at the target)
    next: tuple[float, float, float] = NO_NEXT
    #: LAND: the altitude (AMSL) position_setpoint_triplet.current carries, as PX4's navigator sets
    #: it: the mission's land item's, the Return destination's, Land mode's 0 (set_land_item); NaN:
    #: the goal's z. Logged only: the descent does not follow it
    alt_amsl: float = math.nan


@dataclass(frozen=True, slots=True)
class Limits:
    """The parameters the controller uses, read once per parameter change."""

    cruise: float
    vel_max: float
    vel_manual: float
    acc_hor: float
    jerk: float
    z_up: float
    z_down: float
    z_vel_max_up: float
    z_vel_max_dn: float
    tko_speed: float
    tko_ramp: float
    land_speed: float
    land_alt1: float
    land_alt2: float
    land_alt3: float
    land_crawl: float
    tilt_max: float
    man_tilt_max: float
    man_yaw_max: float
    man_yaw_tau: float
    xy_p: float
    z_p: float
    vxy_p: float
    vxy_i: float
    vxy_d: float
    veld_lp: float
    vz_p: float
    vz_i: float
    acc_up: float
    acc_down: float
    yaw_rate: float
    yaw_acc: float
    err_max: float
    hold_dz: float
    xy_man_expo: float
    z_man_expo: float
    yaw_expo: float
    jerk_max: float
    vel_man_side: float
    vel_man_back: float
    yaw_mode: int
    mis_yaw_err: float  # rad: MPC_YAW_MODE 4 holds the trajectory until the heading is within it
    acc_rad: float
    alt_rad: float
    traj_p: float
    att: YawGains  # mc_att_control's yaw gains

    @classmethod
    def of(cls, p: ParamStore) -> Limits:
        return cls(
            cruise=p["MPC_XY_CRUISE"],
            vel_max=p["MPC_XY_VEL_MAX"],
            vel_manual=p["MPC_VEL_MANUAL"],
            acc_hor=p["MPC_ACC_HOR"],
            jerk=p["MPC_JERK_AUTO"],
            z_up=p["MPC_Z_V_AUTO_UP"],
            z_down=p["MPC_Z_V_AUTO_DN"],
            z_vel_max_up=p["MPC_Z_VEL_MAX_UP"],
            z_vel_max_dn=p["MPC_Z_VEL_MAX_DN"],
            tko_speed=p["MPC_TKO_SPEED"],
            tko_ramp=p["MPC_TKO_RAMP_T"],
            land_speed=p["MPC_LAND_SPEED"],
            land_alt1=p["MPC_LAND_ALT1"],
            land_alt2=p["MPC_LAND_ALT2"],
            land_alt3=p["MPC_LAND_ALT3"],
            land_crawl=p["MPC_LAND_CRWL"],
            tilt_max=math.radians(p["MPC_TILTMAX_AIR"]),
            man_tilt_max=math.radians(p["MPC_MAN_TILT_MAX"]),
            man_yaw_max=math.radians(p["MPC_MAN_Y_MAX"]),
            man_yaw_tau=p["MPC_MAN_Y_TAU"],
            xy_p=p["MPC_XY_P"],
            z_p=p["MPC_Z_P"],
            vxy_p=p["MPC_XY_VEL_P_ACC"],
            vxy_i=p["MPC_XY_VEL_I_ACC"],
            vxy_d=p["MPC_XY_VEL_D_ACC"],
            veld_lp=p["MPC_VELD_LP"],
            vz_p=p["MPC_Z_VEL_P_ACC"],
            vz_i=p["MPC_Z_VEL_I_ACC"],
            acc_up=p["MPC_ACC_UP_MAX"],
            acc_down=p["MPC_ACC_DOWN_MAX"],
            yaw_rate=math.radians(p["MPC_YAWRAUTO_MAX"]),
            yaw_acc=math.radians(p["MPC_YAWRAUTO_ACC"]),
            err_max=max(p["MPC_XY_ERR_MAX"], 0.1),
            hold_dz=p["MPC_HOLD_DZ"],
            xy_man_expo=p["MPC_XY_MAN_EXPO"],
            z_man_expo=p["MPC_Z_MAN_EXPO"],
            yaw_expo=p["MPC_YAW_EXPO"],
            jerk_max=p["MPC_JERK_MAX"],
            vel_man_side=p["MPC_VEL_MAN_SIDE"],
            vel_man_back=p["MPC_VEL_MAN_BACK"],
            yaw_mode=int(p["MPC_YAW_MODE"]),
            mis_yaw_err=math.radians(p["MIS_YAW_ERR"]),
            acc_rad=p["NAV_ACC_RAD"],
            alt_rad=p["NAV_MC_ALT_RAD"],
            traj_p=p["MPC_XY_TRAJ_P"],
            att=YawGains.of(p),
        )


def max_speed_from_distance(jerk: float, accel: float, distance: float, final: float) -> float:
    """``math::computeMaxSpeedFromDistance`` (PX4 TrajMath.hpp): the speed from which the
    jerk-limited trajectory can still slow to ``final`` within ``distance``."""
    b = 4.0 * accel * accel / max(jerk, 1e-3)
    c = -2.0 * accel * distance - final * final
    return max(0.5 * (-b + math.sqrt(b * b - 4.0 * c)), final)


CLAMP_ACCURACY = 0.5  # m/s: PositionSmoothing's accuracy for clampToXYNorm / clampToZNorm


def clamp_to_xy_norm(v: list[float], max_xy: float, accuracy: float) -> list[float]:
    """``clampToXYNorm`` (TrajectoryConstraints.hpp): a 3-D vector whose horizontal part is longer
    than ``max_xy`` scaled down as a whole; only its horizontal part when both are under
    ``accuracy`` (so a vanishing limit does not stop the other axis)."""
    xy = math.hypot(v[0], v[1])
    if xy <= 1e-9 or max_xy >= xy:
        return v
    f = max_xy / xy
    if max_xy < accuracy and xy < accuracy:
        return [v[0] * f, v[1] * f, v[2]]
    return [c * f for c in v]


def clamp_to_z_norm(v: list[float], max_z: float, accuracy: float) -> list[float]:
    """``clampToZNorm``: the same for the vertical part against ``max_z``."""
    z = abs(v[2])
    if z <= 1e-9 or max_z >= z:
        return v
    f = max_z / z
    if max_z < accuracy and z < accuracy:
        return [v[0], v[1], v[2] * f]
    return [c * f for c in v]


def track_target(
    goal: Goal, x: float, y: float, z: float, acc_rad: float, prev: tuple[float, float, float] | None = None
) -> tuple[float, float, float, bool]:
    """Where a POSITION goal's trajectory heads now: FlightTaskAuto's internal waypoints.

    ``FlightTaskAuto::_getCurrentState`` / ``_updateInternalWaypoints`` (PX4 v1.15), in the
    horizontal plane as PX4 checks them since v1.13 ("mc_auto: only check for offtrack, infront and
    behind in XY-plane"): with a previous waypoint, the vehicle follows the line from it to the
    target; when it is more than the acceptance radius beside that line ("offtrack") it heads for
    the closest point of the line first, at the target's altitude (``_closest_pt``), and when the
    previous waypoint is still ahead of it, for that waypoint first. A leg without horizontal
    length has no track. ``prev`` overrides the goal's previous waypoint (the controller's track
    start when the triplet has none). Returns (x, y, z, via): via is True while heading for such an
    internal waypoint.
    """
    px, py, pz = goal.prev if prev is None else prev
    if px != px:
        return goal.x, goal.y, goal.z, False
    ux, uy = goal.x - px, goal.y - py
    length = math.hypot(ux, uy)
    if length < 1e-6:
        return goal.x, goal.y, goal.z, False
    ux, uy = ux / length, uy / length
    if ux * (goal.x - x) + uy * (goal.y - y) < 0.0:  # target behind: straight to it
        return goal.x, goal.y, goal.z, False
    dx, dy = x - px, y - py
    along = ux * dx + uy * dy
    if along < 0.0 and dx * dx + dy * dy > acc_rad * acc_rad:  # previous waypoint in front
        return px, py, pz, True
    cx, cy = px + ux * along, py + uy * along
    ox, oy = x - cx, y - cy
    if ox * ox + oy * oy > acc_rad * acc_rad:  # offtrack: back to the closest point of the track
        return cx, cy, goal.z, True
    return goal.x, goal.y, goal.z, False


def l1_point(
    px: float, py: float, tx: float, ty: float, x: float, y: float, acc_rad: float
) -> tuple[float, float]:
    """``PositionSmoothing::_getL1Point``: on the line from (px, py) to the target, the point an
    L1 distance of max(acceptance radius, 5 m) from (x, y) past its closest point."""
    ux, uy = tx - px, ty - py
    n = math.hypot(ux, uy)
    if n < 1e-6:
        return tx, ty
    ux, uy = ux / n, uy / n
    along = (x - px) * ux + (y - py) * uy
    cx, cy = px + ux * along, py + uy * along
    cross = math.hypot(cx - x, cy - y)
    l1 = max(acc_rad, 5.0)
    ahead = math.sqrt(l1 * l1 - cross * cross) if l1 > cross else 0.0
    return cx + ahead * ux, cy + ahead * uy


def corner_speed(
    start: tuple[float, float, float],
    target: tuple[float, float, float],
    nxt: tuple[float, float, float],
    lim: Limits,
    acc_rad: float,
    cruise: float,
) -> float:
    """The speed PX4 passes ``target`` at on its way from ``start`` (the trajectory's position)
    to ``nxt``: ``computeStartXYSpeedFromWaypoints``' ``speed_at_target`` (PX4 v1.15
    TrajectoryConstraints.hpp). A tangent circle through the corner at MPC_XY_TRAJ_P x MPC_ACC_HOR
    centripetal acceleration and the acceptance radius, sqrt(a r tan(alpha / 2)), no faster than the
    speed from which the next leg can still be stopped in (and than ``cruise``); zero (a stop) when
    the next point is within the acceptance radius of the target, when the target is not reached in
    altitude yet or the next one is at another altitude (NAV_MC_ALT_RAD), or when there is none
    (NaN)."""
    tx, ty, tz = target
    nx, ny, nz = nxt
    d_next = math.hypot(tx - nx, ty - ny)
    if not (d_next > 0.001 and d_next >= acc_rad):
        return 0.0
    if not (abs(tz - start[2]) < lim.alt_rad and abs(nz - tz) < lim.alt_rad):
        return 0.0
    ax, ay = tx - start[0], ty - start[1]
    na = math.hypot(ax, ay)
    cos_alpha = (ax * (tx - nx) + ay * (ty - ny)) / (na * d_next) if na > 1e-6 else 0.0
    alpha = min(math.acos(max(-1.0, min(1.0, cos_alpha))), math.pi - 1e-6)
    in_turn = math.sqrt(lim.traj_p * lim.acc_hor * acc_rad * math.tan(alpha / 2.0))
    exit_speed = min(cruise, max_speed_from_distance(lim.jerk, lim.acc_hor, d_next, 0.0))
    return min(in_turn, exit_speed, cruise)


class Controller:
    """Turns a Goal and the estimated state into acceleration (NED, net of gravity) and yaw-rate commands."""

    def __init__(
        self, limits: Limits, yaw_rate_scale: float = 1.0, px4_yaw: bool = True, px4_vertical: bool = True
    ) -> None:
        self.lim = limits
        self.yaw_rate_scale = yaw_rate_scale
        #: PX4's vertical control (TakeoffHandling's ramp, PositionControl's integrator at
        #: MPC_Z_VEL_I_ACC) for PX4 SIH; False: the Gazebo system's, calibrated with its planner
        self.px4_vertical = px4_vertical
        #: PX4's yaw chain (FlightTaskAuto's setpoint slew and feed-forward, mc_att_control's law)
        #: for PX4 SIH; False: the Gazebo system's rate-limited yaw the local planner was calibrated with
        self.px4_yaw = px4_yaw
        #: the heading the manual modes hold (StickYaw's lock, stabilized's integrated setpoint);
        #: NaN: none (unlocked, or not yet since a manual mode was entered)
        self.yaw_lock = math.nan
        #: flying a manual mode now: entering one starts its yaw stick filter at rest, as PX4's
        #: FlightModeManager constructs a fresh flight task at every mode switch
        self.in_manual = False
        self.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        self.ramp = 0.0  # seconds into the takeoff ramp
        #: seconds into TakeoffHandling's ramp in offboard and the stick modes (no takeoff item): the
        #: vehicle restarts it while it idles on the ground
        self.tko_ramp_s = 1e9
        #: Collision Prevention in position mode (FlightTaskManualPosition): (stick velocity NED,
        #: velocity, yaw) -> allowed velocity setpoint; None when PX4 would not run it
        self.velocity_constraint: (
            Callable[[float, float, float, float, float], tuple[float, float]] | None
        ) = None
        #: distance to the ground from the range finder (m), NaN without one; set by the vehicle
        self.dist_bottom = math.nan
        #: MPC_POS_MODE 0 (FlightTaskManualPosition): the stick velocity straight to the velocity
        #: loop, the position locked once slower than ``hold_max_xy`` (MPC_HOLD_MAX_XY); set by the vehicle
        self.direct_velocity = False
        #: MPC_POS_MODE 4 (FlightTaskManualAcceleration, PX4's default): the stick is an
        #: acceleration (``StickAccelerationXY``, built on entering position mode); set by the vehicle
        self.stick_acceleration = False
        self._stick_acc: StickAccelerationXY | None = None
        self.hold_max_xy = 0.8
        self.xy_locked = False
        #: the last acceleration command (NED, 0 in a hover: ``update``'s), set by the vehicle for the log
        self.acc_sp = (0.0, 0.0, 0.0)
        #: PositionControl's velocity setpoint ``_vel_sp`` (NED) as the velocity loops last used
        #: it: the trajectory's velocity plus MPC_XY_P / MPC_Z_P times the position error, NaN on
        #: an axis without velocity control (altitude and manual modes); logged as
        #: vehicle_local_position_setpoint.vx/vy/vz
        self.vsx = self.vsy = self.vsz = math.nan
        #: a takeoff heading for one of FlightTaskAuto's internal waypoints (``update``): the
        #: land detector then treats it as any other auto setpoint
        self.takeoff_via = False
        #: home's local position (x, y) for MPC_YAW_MODE 1 and 2, NaN until the vehicle has one
        #: (home_position.valid_lpos); set by the vehicle
        self.home_xy = (math.nan, math.nan)
        #: FlightTaskAuto's ``_yaw_sp_aligned`` from the last tick: MPC_YAW_MODE 4 holds the
        #: trajectory while it is False
        self.yaw_aligned = True

    def reset(self, x: float, y: float, z: float, vx: float, vy: float, vz: float, yaw: float) -> None:
        """Restart the reference at the vehicle's state (mode switch, arming)."""
        self._stick_acc = StickAccelerationXY(vx, vy)  # FlightTaskManualAcceleration::activate
        self.px, self.py, self.pz = x, y, z
        self.vx, self.vy, self.vz = vx, vy, vz
        self.ax = self.ay = 0.0
        self.ix = self.iy = self.iz = 0.0
        # MulticopterPositionControl's _vel_x/y_deriv (BlockDerivative, MPC_VELD_LP low-pass)
        self.dvx = self.dvy = 0.0
        self.vx_prev, self.vy_prev = vx, vy
        self.yaw_sp = yaw
        self.yawrate_sp = 0.0
        self.ramp = 0.0
        self.stretch = 1.0
        self.speed_prev = 0.0  # PositionSmoothing's _max_speed_previous
        self.az_ref = 0.0  # the z trajectory's acceleration (jerk-limited)
        self.vz_plan = 0.0  # PositionSmoothing's last unsmoothed z velocity setpoint (its constraints)
        #: FlightTaskAuto's _triplet_prev_wp without a valid previous waypoint: the vehicle's
        #: position when the triplet last changed (``_track_key``)
        self.track_start: tuple[float, float, float] = NO_TRACK
        self._track_key: tuple[float, ...] | None = None

    # ------------------------------------------------------------------ horizontal reference

    def _xy_reference(
        self,
        dt: float,
        tx: float,
        ty: float,
        speed: float,
        x: float,
        y: float,
        final: float = 0.0,
        acc_rad: float = 0.0,
        line: tuple[float, float] | None = None,
        tz: float | None = None,
        hold: bool = False,
    ) -> None:
        """PositionSmoothing towards (tx, ty) and, given ``tz``, the altitude too: then the
        velocity setpoint points straight at the 3-D target (``_generateVelocitySetpoint``), the
        three axes' profiles are synchronized and the vehicle flies a straight line; without it
        (a landing: z is the descent's own) only x and y. ``hold``: a zero velocity setpoint on
        every axis (PositionSmoothing's ``force_zero_velocity_setpoint``)."""
        lim = self.lim
        # PositionSmoothing::_generateTrajectory: while the drone is behind the trajectory, its
        # integration time shrinks with the horizontal distance to it (MPC_XY_ERR_MAX)
        ahead = (self.px - x) * self.vx + (self.py - y) * self.vy < 0.0
        err = math.hypot(self.px - x, self.py - y)
        stretch = 1.0 if ahead else 1.0 - min(err / lim.err_max, 1.0)
        self.stretch = stretch
        dts = dt * stretch
        ex, ey = tx - self.px, ty - self.py
        dist = math.hypot(ex, ey)
        vmax = min(speed, max_speed_from_distance(lim.jerk, lim.acc_hor, dist, final))
        # PositionSmoothing::_isTurning: the trajectory's velocity more than ~11 degrees off the
        # direction to the target (and faster than 0.2 m/s, outside the acceptance radius) is a
        # turn: its speed stays at what it was when the turn began (_max_speed_previous) and it
        # aims at the L1 point 5 m down the line from ``line`` (the previous waypoint) to the target
        v = math.hypot(self.vx, self.vy)
        if v > 0.2 and dist > acc_rad and (self.vx * ex + self.vy * ey) < 0.98 * v * dist:
            vmax = min(vmax, self.speed_prev)
            if line is not None:
                ex, ey = l1_point(line[0], line[1], tx, ty, self.px, self.py, acc_rad)
                ex, ey = ex - self.px, ey - self.py
                dist = math.hypot(ex, ey)
        else:
            self.speed_prev = vmax
        if hold:
            if tz is not None:
                self._smooth_3d(dts, 0.0, 0.0, 0.0, 0.0)
            else:
                self._smooth(dts, 0.0, 0.0)
        elif tz is not None:
            self._smooth_3d(dts, ex, ey, tz - self.pz, vmax)
        else:
            if dist > 1e-6:
                vdx, vdy = ex / dist * vmax, ey / dist * vmax
            else:
                vdx = vdy = 0.0
            self._smooth(dts, vdx, vdy)
        if dist < 0.02 and self.vx * self.vx + self.vy * self.vy < 0.01:
            self.px, self.py, self.vx, self.vy, self.ax, self.ay = tx, ty, 0.0, 0.0, 0.0, 0.0
        if tz is not None and abs(tz - self.pz) < 0.01 and abs(self.vz) < 0.05:
            self.pz, self.vz, self.az_ref = tz, 0.0, 0.0

    def _z_constraints(self) -> tuple[float, float]:
        """FlightTaskAuto::_updateTrajConstraints for z: (MPC_ACC_UP_MAX, MPC_Z_V_AUTO_UP) while the
        last velocity setpoint climbed, else (MPC_ACC_DOWN_MAX, MPC_Z_V_AUTO_DN)."""
        lim = self.lim
        return (lim.acc_up, lim.z_up) if self.vz_plan < 0.0 else (lim.acc_down, lim.z_down)

    def _smooth_3d(self, dts: float, ex: float, ey: float, ez: float, xy_speed: float) -> None:
        """PositionSmoothing's 3-D velocity setpoint and trajectory: towards (ex, ey, ez) from the
        trajectory's position at sqrt(xy_speed^2 + z_speed^2), the whole vector scaled down to
        xy_speed horizontally and to ``_getMaxZSpeed`` vertically (``clampToXYNorm`` /
        ``clampToZNorm``, only the one axis when both are under 0.5 m/s); the z axis a
        VelocitySmoothing profile of its own (MPC_ACC_UP/DOWN_MAX, MPC_Z_V_AUTO_UP/DN,
        MPC_JERK_AUTO), synchronized with x and y."""
        lim = self.lim
        acc_z, vmax_z = self._z_constraints()
        z_speed = min(vmax_z, max_speed_from_distance(lim.jerk, acc_z, abs(ez), 0.0))
        n = math.sqrt(ex * ex + ey * ey + ez * ez)
        if n > 1e-6:
            k = math.sqrt(xy_speed * xy_speed + z_speed * z_speed) / n
            vd = [ex * k, ey * k, ez * k]
        else:
            vd = [0.0, 0.0, 0.0]
        vd = clamp_to_z_norm(clamp_to_xy_norm(vd, xy_speed, CLAMP_ACCURACY), z_speed, CLAMP_ACCURACY)
        self.vz_plan = vd[2]
        fx = velocity_smoothing.plan(self.ax, self.vx, self.px, vd[0], lim.jerk, lim.acc_hor, lim.vel_max)
        fy = velocity_smoothing.plan(self.ay, self.vy, self.py, vd[1], lim.jerk, lim.acc_hor, lim.vel_max)
        fz = velocity_smoothing.plan(self.az_ref, self.vz, self.pz, vd[2], lim.jerk, acc_z, vmax_z)
        velocity_smoothing.synchronize_axes(
            (
                (fx, vd[0], lim.acc_hor, lim.vel_max),
                (fy, vd[1], lim.acc_hor, lim.vel_max),
                (fz, vd[2], acc_z, vmax_z),
            )
        )
        self.ax, self.vx, self.px = velocity_smoothing.advance(fx, dts)
        self.ay, self.vy, self.py = velocity_smoothing.advance(fy, dts)
        self.az_ref, self.vz, self.pz = velocity_smoothing.advance(fz, dts)

    def _smooth(self, dts: float, vdx: float, vdy: float) -> None:
        """PositionSmoothing's x and y trajectories (VelocitySmoothing): a time-optimal
        jerk-limited profile per axis towards the velocity setpoint (MPC_JERK_AUTO, MPC_ACC_HOR
        per axis, MPC_XY_VEL_MAX), the two synchronized to end together, advanced ``dts``."""
        lim = self.lim
        fx = velocity_smoothing.plan(self.ax, self.vx, self.px, vdx, lim.jerk, lim.acc_hor, lim.vel_max)
        fy = velocity_smoothing.plan(self.ay, self.vy, self.py, vdy, lim.jerk, lim.acc_hor, lim.vel_max)
        velocity_smoothing.synchronize(fx, fy, vdx, vdy, lim.acc_hor, lim.vel_max)
        self.ax, self.vx, self.px = velocity_smoothing.advance(fx, dts)
        self.ay, self.vy, self.py = velocity_smoothing.advance(fy, dts)

    def _accelerate(self, dts: float, vdx: float, vdy: float) -> None:
        lim = self.lim
        adx, ady = (vdx - self.vx) * 2.0, (vdy - self.vy) * 2.0
        a = math.hypot(adx, ady)
        if a > lim.acc_hor:
            adx, ady = adx * lim.acc_hor / a, ady * lim.acc_hor / a
        dj = lim.jerk * dts
        self.ax += max(-dj, min(dj, adx - self.ax))
        self.ay += max(-dj, min(dj, ady - self.ay))
        self.vx += self.ax * dts
        self.vy += self.ay * dts

    # ------------------------------------------------------------------ loops

    def _velocity_derivative(self, dt: float, vx: float, vy: float) -> None:
        """The estimated velocity's derivative low-passed at MPC_VELD_LP: PositionControl's
        ``_vel_dot`` (BlockDerivative into BlockLowPass)."""
        b = 2.0 * math.pi * self.lim.veld_lp * dt
        a = b / (1.0 + b)
        self.dvx += a * ((vx - self.vx_prev) / dt - self.dvx)
        self.dvy += a * ((vy - self.vy_prev) / dt - self.dvy)
        self.vx_prev, self.vy_prev = vx, vy

    def _xy_loops(
        self, dt: float, x: float, y: float, vx: float, vy: float, az: float = 0.0
    ) -> tuple[float, float]:
        lim = self.lim
        # the trajectory's velocity is fed forward unstretched (PositionSmoothing's output)
        vcx = self.vx + lim.xy_p * (self.px - x)
        vcy = self.vy + lim.xy_p * (self.py - y)
        self.vsx, self.vsy = vcx, vcy
        return self._velocity_pid(dt, vcx - vx, vcy - vy, az)

    def _velocity_pid(self, dt: float, evx: float, evy: float, az: float) -> tuple[float, float]:
        """``PositionControl::_velocityControl`` horizontally, from the velocity error (NED)."""
        lim = self.lim
        # P + I - D on the velocity's derivative, plus the trajectory's acceleration fed
        # forward; here all but the integrator
        pdx = lim.vxy_p * evx - lim.vxy_d * self.dvx + self.ax
        pdy = lim.vxy_p * evy - lim.vxy_d * self.dvy + self.ay
        if az > 0.0:
            # its tracking anti-windup judges the horizontal acceleration the thrust gives as
            # (g - az) / g of the command (decoupled; the hover thrust estimate cancels out), so a
            # downward vertical setpoint -- the estimate above the true hover thrust -- bleeds the
            # integrator by 2 / MPC_XY_VEL_P_ACC of the shortfall
            k = 2.0 / lim.vxy_p * az / GRAVITY
            evx -= k * (pdx + self.ix)
            evy -= k * (pdy + self.iy)
        # the integrator holds the drag (SIH_KDV); PX4 bounds it only by tracking anti-windup
        imax = GRAVITY * math.tan(lim.tilt_max)
        self.ix = max(-imax, min(imax, self.ix + lim.vxy_i * evx * dt))
        self.iy = max(-imax, min(imax, self.iy + lim.vxy_i * evy * dt))
        return pdx + self.ix, pdy + self.iy

    def _z_loops(
        self,
        dt: float,
        z: float,
        vz: float,
        position: bool,
        feedforward: bool = True,
        auto: bool = False,
        up: float = math.inf,
    ) -> float:
        """PositionControl vertically: the altitude's P (``position``), the climb rate's PI, and
        the trajectory's acceleration fed forward (not during the takeoff ramp, as
        MulticopterPositionControl drops it there). In the auto modes (``auto``) the climb-rate
        setpoint is limited as MulticopterPositionControl's setVelocityLimits does with
        FlightTaskAuto's constraints: up to MPC_Z_VEL_MAX_UP (FlightTaskAuto's 1.2
        MPC_Z_V_AUTO_UP, clamped there), down to max(MPC_Z_VEL_MAX_DN, 1.2 MPC_Z_V_AUTO_DN)."""
        lim = self.lim
        vzc = self.vz + (lim.z_p * (self.pz - z) if position else 0.0)
        if auto or up < math.inf:
            # the auto modes' limits, or TakeoffHandling's upward one: PositionControl's constrain,
            # the lower bound first (a negative upward limit forces the setpoint down)
            down = max(lim.z_vel_max_dn, 1.2 * lim.z_down)
            top = min(up, lim.z_vel_max_up) if auto else up
            vzc = -top if vzc < -top else min(vzc, down)
        self.vsz = vzc
        e = vzc - vz
        if not self.px4_vertical:
            self.iz = max(-4.0, min(4.0, self.iz + Z_I_SCALE * lim.vz_i * e * dt))
            return lim.vz_p * e + self.iz + (self.az_ref if feedforward else 0.0)
        # PositionControl::_velocityControl: the integral within +-g, frozen while the thrust is at
        # its minimum (none before the takeoff ramp ends: ``up`` finite) and the error points down,
        # or at its maximum and the error points up
        az = lim.vz_p * e + self.iz + (self.az_ref if feedforward else 0.0)
        floor = GRAVITY if up < math.inf else AZ_MIN_THRUST
        if not ((az >= floor and e >= 0.0) or (az <= -GRAVITY and e <= 0.0)):
            self.iz = max(-GRAVITY, min(GRAVITY, self.iz + lim.vz_i * e * dt))
        return az

    def _takeoff_ramp(self, seconds: float) -> float:
        """``TakeoffHandling::updateRamp``: the upward climb-rate limit ``seconds`` into the ramp,
        from -g / MPC_Z_VEL_P_ACC (the velocity loop then asks for no thrust) to MPC_Z_VEL_MAX_UP
        (the speed the flight task allows, FlightTaskAuto's 1.2 MPC_Z_V_AUTO_UP clamped there)
        over MPC_TKO_RAMP_T. Negative: the setpoint is held that far downward (PositionControl's
        constrain, the lower bound first)."""
        lim = self.lim
        start = -GRAVITY / max(lim.vz_p, 0.01)
        return start + (lim.z_vel_max_up - start) * min(seconds / max(lim.tko_ramp, 1e-3), 1.0)

    def update_hover_thrust(self, previous: float, new: float) -> None:
        """``PositionControl::updateHoverThrust``: the vertical integrator takes up the change, so
        the thrust is the same before and after the new hover thrust estimate."""
        az = self.acc_sp[2]
        self.iz += (az - GRAVITY) * previous / new + GRAVITY - az

    def _yaw(self, dt: float, yaw: float, target: float) -> float:
        """The yaw rate command towards ``target`` (NaN: hold the setpoint)."""
        lim = self.lim
        self.in_manual = False
        if self.px4_yaw:
            # FlightTaskAuto::_limitYawRate: the setpoint moves towards the target at
            # MPC_YAWRAUTO_MAX at most (no acceleration limit in v1.15's auto modes), and its rate
            # of change, low-passed (AlphaFilter, 0.2 s), is the yawspeed setpoint fed forward
            step = lim.yaw_rate * dt
            d = 0.0 if target != target else max(-step, min(step, wrap_pi(target - self.yaw_sp)))
            self.yaw_sp = wrap_pi(self.yaw_sp + d)
            self.yawrate_sp += (d / dt - self.yawrate_sp) * (dt / (dt + YAWSPEED_FILTER_TAU))
            if lim.yaw_mode == 4:  # only MPC_YAW_MODE 4 waits on it: nothing more per tick else
                # _yaw_sp_aligned: the setpoint within MIS_YAW_ERR of the heading wanted, and
                # turning slower than MPC_YAWRAUTO_MAX
                self.yaw_aligned = (
                    target != target or abs(wrap_pi(target - self.yaw_sp)) < lim.mis_yaw_err
                ) and abs(self.yawrate_sp) < lim.yaw_rate
            return yaw_rate_setpoint(self.yaw_sp, yaw, self.yawrate_sp, lim.att)
        if not math.isnan(target):
            self.yaw_sp = target
        err = wrap_pi(self.yaw_sp - yaw)
        rmax = lim.yaw_rate * self.yaw_rate_scale
        want = max(-rmax, min(rmax, 2.5 * err))
        step = lim.yaw_acc * dt
        self.yawrate_sp += max(-step, min(step, want - self.yawrate_sp))
        return self.yawrate_sp

    def _heading_from_mode(self, tx: float, ty: float, x: float, y: float, acc_rad: float) -> float:
        """The heading (rad) an auto setpoint without one of its own gets from ``MPC_YAW_MODE``
        (``FlightTaskAuto::_set_heading_from_mode``, PX4 v1.15), towards (tx, ty), the (internal)
        target, from (x, y); NaN: hold the heading setpoint. 0 and 4 face the target, 1 home, 2
        away from home, each only from farther than the acceptance radius (inside it the heading
        is locked); 3, and 1 or 2 before there is a home, follow the trajectory's velocity
        (``_generateHeadingAlongTraj``) while it is faster than ``ALONG_TRAJ_SPEED`` and the
        target farther than ``ALONG_TRAJ_DIST``. Called after the trajectory's tick."""
        mode = self.lim.yaw_mode
        if mode == 1 or mode == 2:
            hx, hy = self.home_xy
            dx, dy = (hx - x, hy - y) if mode == 1 else (x - hx, y - hy)
        elif mode == 3:
            dx = dy = math.nan
        else:
            dx, dy = tx - x, ty - y
        if not math.isnan(dx):
            return math.atan2(dy, dx) if dx * dx + dy * dy > acc_rad * acc_rad else math.nan
        if math.hypot(self.vx, self.vy) > ALONG_TRAJ_SPEED and math.hypot(tx - x, ty - y) > ALONG_TRAJ_DIST:
            return math.atan2(self.vy, self.vx)
        return math.nan

    def _track_prev(self, goal: Goal, x: float, y: float, z: float) -> tuple[float, float, float]:
        """The start of the track to ``goal``: its previous waypoint, else, as FlightTaskAuto's
        ``_evaluateTriplets`` does, where the vehicle was when the target (or the previous and next
        waypoints' validity) last changed: a hold, a reposition or a return leg is a line too."""
        if goal.prev[0] == goal.prev[0]:
            self._track_key = None
            return goal.prev
        key = (goal.x, goal.y, goal.z, goal.next[0] == goal.next[0])
        if key != self._track_key:
            self._track_key = key
            self.track_start = (x, y, z)
        return self.track_start

    def _limit_tilt(self, ax: float, ay: float, tilt: float) -> tuple[float, float]:
        amax = GRAVITY * math.tan(tilt)
        a = math.hypot(ax, ay)
        if a > amax:
            return ax * amax / a, ay * amax / a
        return ax, ay

    # ------------------------------------------------------------------ one tick

    def update(
        self, dt: float, goal: Goal, x: float, y: float, z: float, vx: float, vy: float, vz: float, yaw: float
    ) -> tuple[float, float, float, float]:
        """(ax, ay, az, yawrate) commands for one controller tick."""
        lim = self.lim
        kind = goal.kind
        if kind not in (GoalKind.LAND, GoalKind.POSITION, GoalKind.TAKEOFF):
            self.az_ref = 0.0
        if kind is GoalKind.IDLE:
            self.reset(x, y, z, 0.0, 0.0, 0.0, yaw)
            return 0.0, 0.0, GRAVITY, 0.0
        self._velocity_derivative(dt, vx, vy)
        self.takeoff_via = False
        az_top = AZ_MIN_THRUST
        # TakeoffHandling is one state for every mode: a mode entered in the air does not ramp
        self.tko_ramp_s += dt
        if kind is GoalKind.POSITION or kind is GoalKind.TAKEOFF:
            # FlightTaskAuto's track states, for a takeoff triplet too. It has no previous
            # waypoint, so its track starts where the vehicle was when the triplet came, a moment
            # after the navigator took the takeoff point (``Mission::handleTakeoff``, from its own
            # position sample): a centimetre-short track against the way the estimate moved.
            # Drifting more than the acceptance radius behind its start in the climb ("previous in
            # front"), PX4 goes back down to that start on the ground, and climbs again once
            # within the radius (PX4 SIH's takeoff stalls); beside the track it climbs towards
            # its closest point
            acc_rad = goal.acc_rad if goal.acc_rad == goal.acc_rad else lim.acc_rad
            prev = self._track_prev(goal, x, y, z)
            tx, ty, tz, via = track_target(goal, x, y, z, acc_rad, prev)
            self.takeoff_via = via and kind is GoalKind.TAKEOFF
        if kind is GoalKind.POSITION or self.takeoff_via:
            speed = goal.speed if goal.speed == goal.speed else lim.cruise
            speed = min(speed, lim.vel_max)
            # PositionSmoothing's waypoints {trajectory, target, next}: an internal waypoint before
            # the target is passed towards the target; the target towards the triplet's next
            nxt = (goal.x, goal.y, goal.z) if via else goal.next
            final = corner_speed((self.px, self.py, self.pz), (tx, ty, tz), nxt, lim, acc_rad, speed)
            # the line the trajectory follows: from the previous waypoint, or from where the
            # vehicle is when it heads for an internal waypoint first (FlightTaskAuto's _prev_wp)
            line = (x, y) if via else prev[:2]
            # MPC_YAW_MODE 4: FlightTaskAuto forces a zero velocity setpoint until the heading
            # setpoint is aligned (``_yaw_sp_aligned``, from the last tick's _limitYawRate)
            hold = lim.yaw_mode == 4 and not self.yaw_aligned
            self._xy_reference(
                dt, tx, ty, speed, x, y, final=final, acc_rad=acc_rad, line=line, tz=tz, hold=hold
            )
            target_yaw = goal.yaw
            if math.isnan(target_yaw):
                target_yaw = self._heading_from_mode(tx, ty, x, y, acc_rad)
            az = self._z_loops(dt, z, vz, True, auto=True)
            ax, ay = self._xy_loops(dt, x, y, vx, vy, az)
        elif kind is GoalKind.TAKEOFF:
            self.ramp += dt
            h = self.dist_bottom if self.dist_bottom == self.dist_bottom else -z
            # FlightTaskAuto::_updateTrajConstraints: the takeoff speed and its ramp only below
            # MPC_LAND_ALT1; above, the takeoff point is a waypoint like any other (MPC_Z_V_AUTO_UP,
            # MPC_ACC_UP_MAX) and the altitude is tracked
            high = h >= lim.land_alt1
            if high:
                self._xy_reference(dt, goal.x, goal.y, lim.cruise, x, y, acc_rad=lim.acc_rad, tz=goal.z)
            else:
                self._xy_reference(dt, goal.x, goal.y, lim.cruise, x, y, acc_rad=lim.acc_rad)
                # below it PositionSmoothing's z axis climbs at MPC_TKO_SPEED, accelerating and
                # braking at MPC_TKO_SPEED / MPC_TKO_RAMP_T at most (jerk-limited), from the
                # vehicle's altitude (forceSetPosition holds the trajectory there)
                climb = lim.tko_speed
                acc = min(lim.acc_up, lim.tko_speed / max(lim.tko_ramp, 1e-3))
                self.pz = z
                vd = -min(climb, max_speed_from_distance(lim.jerk, acc, max(z - goal.z, 0.0), 0.0))
                self.vz_plan = vd
                fz = velocity_smoothing.plan(self.az_ref, self.vz, self.pz, vd, lim.jerk, acc, climb)
                self.az_ref, self.vz, _ = velocity_smoothing.advance(fz, dt)
                # mc_pos_control's takeoff ramp: the climb-rate setpoint starts below hover
                # (+0.7 m/s down) and its limit rises at MPC_TKO_SPEED / MPC_TKO_RAMP_T
                ramped = TKO_RAMP_START - climb / max(lim.tko_ramp, 1e-3) * self.ramp
                if ramped > self.vz:
                    self.vz, self.az_ref = ramped, 0.0
            target_yaw = goal.yaw
            if math.isnan(target_yaw):
                # FlightTaskAuto::_set_heading_from_mode in the takeoff too: with MPC_YAW_MODE 0,
                # drifted farther than the acceptance radius from the takeoff point, the vehicle
                # turns to face it
                target_yaw = self._heading_from_mode(goal.x, goal.y, x, y, lim.acc_rad)
            up = math.inf
            if self.px4_vertical and self.ramp < lim.tko_ramp:
                up = self._takeoff_ramp(self.ramp)
                az_top = GRAVITY  # the thrust may be zero until the ramp ends (MPC_THR_MIN after)
            az = self._z_loops(dt, z, vz, high, feedforward=self.ramp >= lim.tko_ramp, auto=True, up=up)
            ax, ay = self._xy_loops(dt, x, y, vx, vy, az)
        elif kind is GoalKind.LAND:
            self._xy_reference(dt, goal.x, goal.y, lim.cruise, x, y, acc_rad=lim.acc_rad)
            # FlightTaskAuto's _dist_to_ground: the range finder's distance (SIH has one) when
            # the vehicle sets it, else the estimated altitude above home
            h = self.dist_bottom if self.dist_bottom == self.dist_bottom else -z
            # FlightTaskAuto::_prepareLandSetpoints: MPC_LAND_SPEED below MPC_LAND_ALT2 rising to
            # MPC_Z_VEL_MAX_DN at MPC_LAND_ALT1, MPC_LAND_CRWL within MPC_LAND_ALT3 of the ground
            # by the range finder; PositionSmoothing's z axis then caps it at MPC_Z_V_AUTO_DN
            if h > lim.land_alt1:
                v = lim.z_vel_max_dn
            elif h > lim.land_alt2:
                f = (h - lim.land_alt2) / max(lim.land_alt1 - lim.land_alt2, 1e-3)
                v = lim.land_speed + (lim.z_vel_max_dn - lim.land_speed) * f
            else:
                v = lim.land_speed
            if self.dist_bottom == self.dist_bottom and self.dist_bottom <= lim.land_alt3:
                v = lim.land_crawl
            v = min(v, lim.z_down)
            # PositionSmoothing's z axis (VelocitySmoothing): jerk-limited at MPC_JERK_AUTO up to
            # MPC_ACC_DOWN_MAX (PX4 SIH: the descent starts and slows to MPC_LAND_CRWL at +-4 m/s^3)
            dv = v - self.vz
            want = math.copysign(min(lim.acc_down, math.sqrt(2.0 * lim.jerk * abs(dv))), dv)
            jstep = lim.jerk * dt
            self.az_ref += max(-jstep, min(jstep, want - self.az_ref))
            self.vz += self.az_ref * dt
            # FlightTaskAuto::_prepareLandSetpoints gives PositionSmoothing a velocity target
            # only (z NaN), but the smoothed trajectory integrates its own position and
            # PositionControl tracks both: a vehicle lagging the descent catches up (PX4 SIH's
            # descent from 10 m takes ~14 s, not the ~18 s of velocity control alone)
            self.pz += self.vz * dt
            target_yaw = goal.yaw
            az = self._z_loops(dt, z, vz, True, auto=True)
            ax, ay = self._xy_loops(dt, x, y, vx, vy, az)
        elif kind is GoalKind.OFFBOARD:
            return self._offboard(dt, goal, x, y, z, vx, vy, vz, yaw)
        else:
            return self._manual(dt, goal, x, y, z, vx, vy, vz, yaw)
        ax, ay = self._limit_tilt(ax, ay, lim.tilt_max)
        az = max(-GRAVITY, min(az_top, az))
        return ax, ay, az, self._yaw(dt, yaw, target_yaw)

    def _offboard(
        self, dt: float, goal: Goal, x: float, y: float, z: float, vx: float, vy: float, vz: float, yaw: float
    ) -> tuple[float, float, float, float]:
        """An offboard trajectory_setpoint straight into position control, as PX4 v1.15.

        PX4 runs no flight task in offboard: ``MulticopterPositionControl`` feeds the setpoint to
        ``PositionControl`` (src/lib/.../PositionControl.cpp ``_positionControl``): the velocity
        setpoint is the feed-forward velocity plus ``MPC_XY_P`` / ``MPC_Z_P`` times the position
        error (axes without a position or velocity hold still), limited to ``MPC_XY_VEL_MAX``
        horizontally and ``MPC_Z_VEL_MAX_UP`` / ``_DN`` vertically (offboard overrides the auto
        speeds with these); the upward limit ramps up over ``MPC_TKO_RAMP_T`` after a takeoff
        from the ground (``TakeoffHandling``). The velocity loops and tilt limit then apply as in
        every mode. No smoothing: PX4 does not apply ``MPC_ACC_HOR`` / jerk in offboard either.
        """
        lim = self.lim
        fx, fy, fz = goal.vel
        px, py, pz = goal.x, goal.y, goal.z
        cx = (fx if fx == fx else 0.0) + (lim.xy_p * (px - x) if px == px else 0.0)
        cy = (fy if fy == fy else 0.0) + (lim.xy_p * (py - y) if py == py else 0.0)
        cz = (fz if fz == fz else 0.0) + (lim.z_p * (pz - z) if pz == pz else 0.0)
        v = math.hypot(cx, cy)
        if v > lim.vel_max:
            cx, cy = cx * lim.vel_max / v, cy * lim.vel_max / v
        up = lim.z_vel_max_up
        if self.tko_ramp_s < lim.tko_ramp:
            if self.px4_vertical:
                up = self._takeoff_ramp(self.tko_ramp_s)
            else:
                up = -TKO_RAMP_START + (up + TKO_RAMP_START) * self.tko_ramp_s / max(lim.tko_ramp, 1e-3)
        cz = -up if cz < -up else min(lim.z_vel_max_dn, cz)
        # logged as trajectory_setpoint: the client's position, the limited velocity setpoint
        self.px, self.py, self.pz = px, py, pz
        self.vx, self.vy, self.vz = cx, cy, cz
        self.ax = self.ay = 0.0
        self.stretch = 1.0
        az = self._z_loops(dt, z, vz, False)
        self.vsx, self.vsy = cx, cy
        ax, ay = self._limit_tilt(*self._velocity_pid(dt, cx - vx, cy - vy, az), lim.tilt_max)
        self.in_manual = False
        if goal.yawspeed == goal.yawspeed and goal.yaw != goal.yaw:
            # PositionControl: no yaw, so the yaw setpoint is the heading and the rate is fed forward
            self.yaw_sp = yaw
            self.yawrate_sp = goal.yawspeed
            yr = goal.yawspeed
        elif self.px4_yaw:
            # no flight task in offboard: the client's yaw (and yawspeed, fed forward) go to the
            # attitude controller as they are, limited only by MC_YAWRATE_MAX
            if goal.yaw == goal.yaw:
                self.yaw_sp = goal.yaw
            self.yawrate_sp = goal.yawspeed if goal.yawspeed == goal.yawspeed else 0.0
            yr = yaw_rate_setpoint(self.yaw_sp, yaw, self.yawrate_sp, lim.att)
        else:
            yr = self._yaw(dt, yaw, goal.yaw)
        return ax, ay, max(-GRAVITY, min(AZ_MIN_THRUST, az)), yr

    def _manual(
        self, dt: float, goal: Goal, x: float, y: float, z: float, vx: float, vy: float, vz: float, yaw: float
    ) -> tuple[float, float, float, float]:
        lim = self.lim
        sx, sy, sz, sr = goal.sticks
        dz = lim.hold_dz
        climb = (sz - 0.5) * 2.0
        if goal.kind is not GoalKind.ATTITUDE:
            # altitude and position mode (FlightTaskManualAltitude and on): Sticks' deadzone and
            # expo; the position task's pitch / roll too, below
            climb = expo_deadzone(climb, lim.z_man_expo, dz)
            sr = expo_deadzone(sr, lim.yaw_expo, dz)
        else:
            sr = 0.0 if abs(sr) < dz else sr
        ex, ey = expo_deadzone(sx, lim.xy_man_expo, dz), expo_deadzone(sy, lim.xy_man_expo, dz)
        sx = 0.0 if abs(sx) < dz else sx  # stabilized mode's tilt
        sy = 0.0 if abs(sy) < dz else sy
        c, s = math.cos(yaw), math.sin(yaw)
        if not self.in_manual:  # a manual mode just entered: its flight task starts at rest
            self.in_manual = True
            self.yaw_lock = math.nan
            self.yawrate_sp = 0.0
            self._stick_acc = StickAccelerationXY(self.vx, self.vy, self.ax, self.ay)
        yr = self._stick_yaw(dt, sr, yaw)
        if goal.vel[2] == goal.vel[2]:  # FlightTaskDescend: a set sink rate, not a stick
            self.vz = goal.vel[2]
            climb = -1.0 if goal.vel[2] > 0.0 else 1.0
        else:  # climb rate (altitude and position mode): MPC_Z_VEL_MAX_UP / _DN at full stick
            self.vz = -climb * (lim.z_vel_max_up if climb > 0 else lim.z_vel_max_dn)
        if climb == 0.0 and abs(vz) < 0.3 and abs(self.pz - z) > 1.0:
            self.pz = z
        position_hold = climb == 0.0
        if not position_hold:
            self.pz = z
        up, az_top = math.inf, AZ_MIN_THRUST
        if self.px4_vertical and goal.kind is not GoalKind.ATTITUDE and self.tko_ramp_s < lim.tko_ramp:
            # a takeoff from the ground with the stick: TakeoffHandling's ramp as in the auto modes
            up, az_top = self._takeoff_ramp(self.tko_ramp_s), GRAVITY
        az = self._z_loops(dt, z, vz, position_hold, up=up)
        if goal.kind is GoalKind.ALTITUDE:
            # StickTiltXY: the raw sticks (no deadzone), no longer than 1, are an acceleration,
            # tan(MPC_MAN_TILT_MAX) g at full stick (0.02-3 g), turned by the locked heading
            # (MC_MAN_TILT_TAU's filter: not modelled, 0 by default)
            rx, ry = limit_unit_length(goal.sticks[0], goal.sticks[1])
            full = max(0.02, min(3.0, math.tan(min(lim.man_tilt_max, math.radians(89.0))))) * GRAVITY
            heading = self.yaw_lock if self.yaw_lock == self.yaw_lock else yaw
            ch, sh = math.cos(heading), math.sin(heading)
            bx, by = rx * full, ry * full
            self.px, self.py, self.vx, self.vy = x, y, vx, vy
            self.vsx = self.vsy = math.nan  # tilt from the sticks: no horizontal velocity control
            return ch * bx - sh * by, sh * bx + ch * by, max(-GRAVITY, min(az_top, az)), yr
        self.stretch = 1.0
        if self.stick_acceleration and not self.direct_velocity and self._stick_acc is not None:
            # MPC_POS_MODE 4: the stick is an acceleration, turned by the locked heading
            sa = self._stick_acc
            heading = self.yaw_lock if self.yaw_lock == self.yaw_lock else yaw
            sa.update(
                ex, ey, heading, x, y, (self.vsx, self.vsy), dt,
                vel_manual=lim.vel_manual, acc_hor=lim.acc_hor, jerk_max=lim.jerk_max,
                tilt_max=lim.tilt_max, vel_man_side=lim.vel_man_side, vel_man_back=lim.vel_man_back,
            )  # fmt: skip
            self.vx, self.vy, self.ax, self.ay = sa.vx, sa.vy, sa.ax, sa.ay
            self.px, self.py = (sa.px, sa.py) if sa.locked else (x, y)
            ax, ay = self._xy_loops(dt, x, y, vx, vy, az)
            ax, ay = self._limit_tilt(ax, ay, lim.tilt_max)
            return ax, ay, max(-GRAVITY, min(az_top, az)), yr
        # position mode 0 and 3: the (expo'd) sticks are a body-frame velocity
        ex, ey = limit_unit_length(ex, ey)
        bvx, bvy = ex * lim.vel_manual, ey * lim.vel_manual
        wx, wy = c * bvx - s * bvy, s * bvx + c * bvy
        if self.velocity_constraint is not None:
            wx, wy = self.velocity_constraint(wx, wy, vx, vy, yaw)
        if self.direct_velocity:
            self._direct_velocity(wx, wy, x, y, vx, vy)
        else:
            self._accelerate(dt, wx, wy)
            if wx == 0.0 and wy == 0.0:  # centred sticks, or CP's zero: brake and hold
                self.px += self.vx * dt
                self.py += self.vy * dt
            else:
                self.px, self.py = x + self.vx * 0.2, y + self.vy * 0.2
        ax, ay = self._xy_loops(dt, x, y, vx, vy, az)
        ax, ay = self._limit_tilt(ax, ay, lim.tilt_max)
        return ax, ay, max(-GRAVITY, min(az_top, az)), yr

    def _stick_yaw(self, dt: float, stick: float, yaw: float) -> float:
        """The yaw rate command of the altitude and position modes from the yaw stick.

        PX4's ``StickYaw``: the stick's rate (MPC_MAN_Y_MAX) low-passed at MPC_MAN_Y_TAU is the
        yawspeed setpoint, fed forward with no yaw setpoint while it is not zero; once it has
        decayed the heading is locked where it is and held (mc_att_control's MC_YAW_P)."""
        lim = self.lim
        if not self.px4_yaw:
            self.yaw_sp = yaw
            self.yawrate_sp = stick * lim.man_yaw_max
            return self.yawrate_sp
        self.yawrate_sp += (stick * lim.man_yaw_max - self.yawrate_sp) * (dt / (dt + lim.man_yaw_tau))
        if abs(self.yawrate_sp) > 1e-7:  # StickYaw::updateYawLock: FLT_EPSILON
            self.yaw_lock = math.nan
            self.yaw_sp = yaw
            return yaw_rate_setpoint(yaw, yaw, self.yawrate_sp, lim.att)
        self.yawrate_sp = 0.0
        if self.yaw_lock != self.yaw_lock:
            self.yaw_lock = yaw
        self.yaw_sp = self.yaw_lock
        return yaw_rate_setpoint(self.yaw_lock, yaw, math.nan, lim.att)

    def _direct_velocity(self, wx: float, wy: float, x: float, y: float, vx: float, vy: float) -> None:
        """FlightTaskManualPosition (MPC_POS_MODE 0): the velocity setpoint as the sticks (and
        Collision Prevention) give it, no acceleration or jerk limit; with a zero setpoint the
        position is locked once the vehicle is slower than MPC_HOLD_MAX_XY (``_updateXYlock``),
        before that only the velocity is controlled."""
        self.vx, self.vy, self.ax, self.ay = wx, wy, 0.0, 0.0
        if wx != 0.0 or wy != 0.0:
            self.xy_locked = False
        elif not self.xy_locked and (self.hold_max_xy <= 0.0 or math.hypot(vx, vy) < self.hold_max_xy):
            self.xy_locked = True
            self.px, self.py = x, y
        if not self.xy_locked:
            self.px, self.py = x, y


#: the controller's output with the motors off: no tilt, thrust balancing gravity, no yaw rate
IDLE = (0.0, 0.0, GRAVITY, 0.0)
