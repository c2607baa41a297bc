"""The multicopter's body and world: point mass with attitude-limited thrust, drag, wind, boxes.

Plain float arithmetic only: one ``Body.step`` is a few dozen float operations, run at 250 Hz.
The model: the commanded acceleration (from the position controller) is reached through a
first-order attitude response (tilt time constant) and limited by the tilt limit; drag is
linear plus quadratic in the air-relative velocity; wind is a mean plus Ornstein-Uhlenbeck
gusts (seeded); the ground is z = 0 (NED, Down positive). Obstacles are Aerialist boxes
(size l, w, h; centre x, y; base z measured up; yaw r degrees). Touching a box is a crash.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from dataclasses import dataclass

from uavtest.sitl.mc_rate_control import I_FACTOR_RATE, YawRateGains
from uavtest.spec.models import Obstacle, Wind

__all__ = ["GRAVITY", "HOVER_THRUST", "Body", "Box", "WindModel", "World"]

GRAVITY = 9.80665
#: PX4 SIH's attitude response: in all nine shared SIH logs the body's tilt (vehicle_attitude)
#: follows the direction of the thrust setpoint (vehicle_local_position_setpoint.thrust) after a
#: 0.09-0.10 s delay and a 0.06 s first-order lag (best fit, ~0.01 rms of the tilt's sine): PX4's
#: attitude and rate controllers, control allocation and SIH's motors between them; in the 24
#: flights flown here at stop 31, 0.09 + 0.07-0.09 s (median per mission). The fit depends on what
#: the setpoint does: with 0.10 + 0.06 here the built-in vehicle's own log fitted as 0.11 + 0.04
#: after stop 29's smoother estimate; with these it fits as 0.09 + 0.08
#: (``uavtest.analysis.attitude_response``)
ATTITUDE_DELAY = 0.08  # s
TAU_TILT = 0.09  # s
#: the competition's system under test (PX4 in Gazebo, iris; the local planner's calibration):
#: a first-order horizontal acceleration response without delay
TAU_TILT_GAZEBO = 0.12  # s
TAU_THRUST = 0.05  # s: SIH_T_TAU, the motors' lag: the vertical thrust's response, and the yaw torque's
DRAG_LINEAR = 1.0  # 1/s: PX4 SIH's first-order drag, SIH_KDV / SIH_MASS (1.0 N s/m / 1 kg)
DRAG_QUADRATIC = 0.0  # 1/m: SIH has none
#: the competition's system under test flies Gazebo's iris, far less draggy than SIH: (linear 1/s,
#: quadratic 1/m) as calibrated against the competition's own local-planner flights
DRAG_GAZEBO_IRIS = (0.15, 0.06)
DRAG_VERTICAL = 0.8  # 1/s
#: PX4 SIH's yaw (``sih.cpp``, the quadrotor's defaults): the yaw moment is SIH_Q_MAX (0.1 N m) x
#: (u0 + u1 - u2 - u3) of the motor commands, which reach them through SIH_T_TAU's lag (``TAU_THRUST``). PX4's
#: control allocation normalises its yaw column (``ControlAllocationPseudoInverse``, the multirotor's
#: normalize_rpy): one unit of normalised yaw torque moves each rotor's command by one unit, so it is
#: 4 x 0.1 N m; with SIH_IZZ 0.03 kg m^2 that is this angular acceleration (rad/s^2). The sequential
#: desaturation gives in on yaw first: the rotors' differential stays within the collective's
#: headroom. SIH_KDW (0.025 N m s) damps the rate.
YAW_TORQUE_GAIN = 4 * 0.1 / 0.03
YAW_DAMPING = 0.025 / 0.03  # 1/s
#: the competition's system under test (Gazebo, iris): its yaw rate follows the command with this lag
TAU_YAW_GAZEBO = 0.08  # s
#: the collective thrust (0..1) that holds SIH's quadrotor up: SIH_MASS * g / (4 * SIH_T_MAX)
HOVER_THRUST = 1.0 * GRAVITY / (4 * 5.0)
#: m/s^2 of net upward thrust the Gazebo system needs to leave the ground (its local planner's
#: flights were calibrated with it). PX4 SIH's fake ground lets go as soon as the thrust outweighs
#: gravity (``sih.cpp``: grounded while ``_v_I_dot(2) > 0``): ``Body.liftoff_acc`` 0
LIFTOFF_ACC_GAZEBO = 3.0
#: PX4's roll and pitch rate integrators wind up against SIH's ground (``sih.cpp`` holds a grounded
#: body still, its rates at zero: level as it stands before a takeoff), from when the land detector
#: stops saying (maybe) landed, the takeoff ramp, until the thrust lifts the body
#: (``RateControl::update`` integrates while not landed); the body is let go with that torque stored
#: and overshoots. 24 PX4 v1.15 SIH flights of the competition missions flown here (their ground
#: truth, 2026-11-28): the true tilt peaks 0.24 s after the release at 10.6 degrees (median;
#: 6.4-18.8, 10th-90th percentile) where the attitude setpoint asked 3.8, its peak in the direction
#: of the released phase's integral of the acceleration setpoint's tilt (4.6 degree-seconds median
#: over 1.8 s; peak = 2.5 x that, R^2 0.73; with the rate integrators' own attitude error, 1.25 x +
#: 1.05 x the setpoint, R^2 0.97) and gone by 0.6 s; within 3 s of lift-off the vehicle truly moves
#: 0.36 m (median; p90 0.72) where a body let go level moved 0.14. Modelled as a pulse of
#: acceleration in that direction, ``KICK_GAIN`` x g x the integral at its peak, shaped (t /
#: KICK_TAU)^2 exp(2 (1 - t / KICK_TAU)) from the release (the position loop's answer, which PX4's
#: busy attitude loop delays, narrows the body's tilt to 0.1-0.5 s): the tilt then peaks at 8.6
#: degrees (median, estimated; the shared logs 6.9, these 24 flights 10.1), the vehicle moves 0.30 m
#: within 3 s and is 0.34 / 0.40 / 0.46 m off its takeoff point at 4 / 6 / 8 m up (PX4 0.28 / 0.40 /
#: 0.41). Measured again at stop 45 (2026-11-29) on 96 PX4 flights of the same missions' plans,
#: both read the same way (``analysis.liftoff``: the true tilt's peak from 0.3 s before to 1 s after
#: the truth rose 2 cm): PX4's peak is 8.2 degrees (median; 3.8-17.2 p10-p90), its truth 0.21 / 0.30 /
#: 0.36 m off 0.67 / 1.5 / 3 s after the release, its estimate 0.20 m (p90 0.43) from the takeoff
#: setpoint 0.3 m up. At 2.5 (with ``ekf2.TILT_SIGMA_ARMED`` 2.3 degrees) the built-in's were 11.3
#: (3.3-19.2), 0.31 / 0.42 / 0.42 m and 0.31 (0.58) over 100 seeds, and its climb wandered 0.45 m
#: (p90 0.75; PX4 0.37, 0.52); at 2.0 (and 1.75 degrees) 8.5 (3.1-13.7), 0.23 / 0.33 / 0.37, 0.22
#: (0.43) and 0.35 (0.59)
KICK_GAIN = 2.0  # 1/s: peak tilt (rad) per rad-second of wound-up tilt command
KICK_TAU = 0.3  # s
KICK_END = 2.0  # s after the release
#: the wound-up tilt command's bound (rad s): PX4's integrator stops at MC_RR_INT_LIM (0.3) of
#: normalised torque, which grows at MC_ROLLRATE_I (0.2) x MC_ROLL_P (6.5) per rad-second of
#: attitude error (the defaults; the pitch axis's are the same)
KICK_WINDUP_MAX = 0.3 / (0.2 * 6.5)
NEAR_MARGIN = 8.0  # m: boxes within this of the vehicle are checked every physics step


@dataclass(frozen=True, slots=True)
class Box:
    """An obstacle precomputed for fast tests: centre, yaw cos/sin, half sizes, Down limits."""

    index: int
    cx: float
    cy: float
    cos: float
    sin: float
    hl: float
    hw: float
    z_top: float  # Down coordinate of the top (negative: above ground)
    z_bottom: float  # Down coordinate of the base
    radius: float  # horizontal bounding radius

    @classmethod
    def of(cls, index: int, o: Obstacle) -> Box:
        r = math.radians(o.position.r)
        hl, hw = o.size.l / 2, o.size.w / 2
        return cls(
            index,
            o.position.x,
            o.position.y,
            math.cos(r),
            math.sin(r),
            hl,
            hw,
            -(o.position.z + o.size.h),
            -o.position.z,
            math.hypot(hl, hw),
        )

    def contains(self, x: float, y: float, z: float) -> bool:
        if z < self.z_top or z > self.z_bottom:
            return False
        dx, dy = x - self.cx, y - self.cy
        u = self.cos * dx + self.sin * dy
        if u > self.hl or u < -self.hl:
            return False
        v = -self.sin * dx + self.cos * dy
        return -self.hw <= v <= self.hw

    def ray(self, x: float, y: float, z: float, dx: float, dy: float, dz: float) -> float:
        """Distance along the unit direction (dx, dy, dz) from (x, y, z) (NED) to this box's
        surface; ``inf`` if the ray misses it; 0 from inside. Slab method in the box's frame."""
        px, py = x - self.cx, y - self.cy
        c, s = self.cos, self.sin
        origin = (c * px + s * py, -s * px + c * py, z - (self.z_top + self.z_bottom) / 2)
        direction = (c * dx + s * dy, -s * dx + c * dy, dz)
        half = (self.hl, self.hw, (self.z_bottom - self.z_top) / 2)
        near, far = 0.0, math.inf
        for o, d, h in zip(origin, direction, half, strict=True):
            if abs(d) < 1e-12:
                if o < -h or o > h:
                    return math.inf
                continue
            t1, t2 = (-h - o) / d, (h - o) / d
            if t1 > t2:
                t1, t2 = t2, t1
            near, far = max(near, t1), min(far, t2)
            if near > far:
                return math.inf
        return near


class World:
    """The boxes, with a cheap 'near' list refreshed at a low rate."""

    def __init__(self, obstacles: Sequence[Obstacle]) -> None:
        self.boxes = [Box.of(i, o) for i, o in enumerate(obstacles)]
        self.near: list[Box] = []

    def refresh_near(self, x: float, y: float) -> None:
        self.near = [b for b in self.boxes if math.hypot(x - b.cx, y - b.cy) <= b.radius + NEAR_MARGIN]

    def hit(self, x: float, y: float, z: float) -> Box | None:
        for b in self.near:
            if b.contains(x, y, z):
                return b
        return None

    def ray(self, x: float, y: float, z: float, dx: float, dy: float, dz: float, max_range: float) -> float:
        """Distance along the unit direction (dx, dy, dz) to the first box, ``inf`` if none is
        within ``max_range`` (what a range sensor or depth camera pixel sees; the ground is not
        an obstacle). Checks every box whose bounding circle is within reach."""
        best = math.inf
        for b in self.boxes:
            if math.hypot(x - b.cx, y - b.cy) - b.radius > max_range:
                continue
            d = b.ray(x, y, z, dx, dy, dz)
            if d < best:
                best = d
        return best if best <= max_range else math.inf


class WindModel:
    """Wind in NED (m/s, the velocity of the air): mean plus OU gusts, never above max speed."""

    TAU = 3.0  # s, gust correlation time

    def __init__(self, wind: Wind, rng: random.Random) -> None:
        d = math.radians(wind.direction)
        self.mean = (wind.mean_speed * math.cos(d), wind.mean_speed * math.sin(d))
        self.max_speed = wind.max_speed if wind.max_speed is not None else wind.mean_speed
        spread = self.max_speed - wind.mean_speed
        self.sigma = spread / 2.0 if wind.gusts else 0.0
        self.gust = [0.0, 0.0, 0.0]
        self._rng = rng
        self.n, self.e, self.d = self.mean[0], self.mean[1], 0.0

    def update(self, dt: float) -> None:
        if self.sigma <= 0:
            return
        a = math.exp(-dt / self.TAU)
        b = self.sigma * math.sqrt(1 - a * a)
        g = self.gust
        gauss = self._rng.gauss
        g[0] = a * g[0] + b * gauss(0.0, 1.0)
        g[1] = a * g[1] + b * gauss(0.0, 1.0)
        g[2] = a * g[2] + 0.25 * b * gauss(0.0, 1.0)
        n, e = self.mean[0] + g[0], self.mean[1] + g[1]
        speed = math.hypot(n, e)
        if speed > self.max_speed > 0:
            n, e = n * self.max_speed / speed, e * self.max_speed / speed
        self.n, self.e, self.d = n, e, g[2]


class Body:
    """Position, velocity, actual acceleration and yaw of the vehicle (NED, SI units)."""

    __slots__ = (
        "ax",
        "ay",
        "az",
        "azt",
        "cax",
        "cay",
        "caz",
        "czt",
        "delay_i",
        "delay_x",
        "delay_y",
        "delay_z",
        "kax",
        "kay",
        "kaz",
        "kick_s",
        "kick_x",
        "kick_y",
        "kl",
        "kq",
        "kx",
        "ky",
        "lean_x",
        "lean_y",
        "liftoff_acc",
        "motors",
        "on_ground",
        "rate_integrating",
        "tau_tilt",
        "vx",
        "vy",
        "vz",
        "windup",
        "wx",
        "wy",
        "x",
        "y",
        "yaw",
        "yaw_int",
        "yaw_rate_gains",
        "yaw_torque",
        "yawrate",
        "z",
    )

    def __init__(
        self,
        tau_tilt: float = TAU_TILT,
        drag_scale: float = 1.0,
        drag: tuple[float, float] = (DRAG_LINEAR, DRAG_QUADRATIC),
        delay_steps: int = 0,
        yaw_rate_gains: YawRateGains | None = None,
        liftoff_acc: float = 0.0,
        windup: bool = False,
    ) -> None:
        self.x = self.y = self.z = 0.0
        self.vx = self.vy = self.vz = 0.0
        self.ax = self.ay = self.az = 0.0  # acceleration from thrust (without gravity), NED
        #: the kinematic acceleration of the last step (thrust, drag and gravity; NED): what SIH
        #: logs as the ground truth's ``ax, ay, az`` (``_v_I_dot``) and EKF2 as the estimate's
        self.kax = self.kay = self.kaz = 0.0
        # what the acceleration is moving toward (the delayed command of the last step): its rate
        self.cax = self.cay = self.caz = 0.0
        #: the vertical acceleration as the attitude sees it, and what it moves toward: the thrust
        #: setpoint's direction reaches the body through the attitude loops (delay, ``tau_tilt``)
        #: as its horizontal part does, while the collective reaches the motors within
        #: SIH_T_TAU; ``tilt`` is that direction
        self.azt = self.czt = 0.0
        self.yaw = 0.0
        self.yawrate = 0.0
        #: PX4's yaw rate loop and SIH's yaw torque (``mc_rate_control``); None: the Gazebo
        #: system's first-order yaw rate response (``TAU_YAW_GAZEBO``)
        self.yaw_rate_gains = yaw_rate_gains
        self.yaw_int = 0.0  # the rate loop's integral (normalised torque)
        self.yaw_torque = 0.0  # the normalised yaw torque the motors give (SIH_T_TAU behind)
        self.on_ground = True
        #: net upward acceleration (m/s^2) the thrust must give before the ground lets go
        self.liftoff_acc = liftoff_acc
        self.motors = False
        self.tau_tilt = tau_tilt
        self.kl = drag[0] * drag_scale
        self.kq = drag[1] * drag_scale
        # the horizontal acceleration commands of the last ``delay_steps`` physics steps (a ring)
        self.delay_x = [0.0] * delay_steps
        self.delay_y = [0.0] * delay_steps
        self.delay_z = [0.0] * delay_steps
        self.delay_i = 0
        #: PX4 SIH's ground and rate integrators (``KICK_GAIN``): the ground holds the body still,
        #: the integrators wind up while ``rate_integrating`` (the vehicle sets it: the land
        #: detector says neither landed nor maybe landed) and kick the body when it lifts off.
        #: False: the Gazebo system's body, whose tilt follows the command on the ground too
        self.windup = windup
        self.rate_integrating = False
        self.wx = self.wy = 0.0  # the wound-up tilt command, rad s (NED)
        self.kick_s = -1.0  # seconds since the release; < 0: no kick
        self.kick_x = self.kick_y = 0.0  # the kick's peak, m/s^2 of horizontal acceleration
        self.kx = self.ky = 0.0  # the kick's acceleration now
        #: EKF2's tilt error (rad, NED: as horizontal acceleration / g; ``ekf2.Estimator.tx``):
        #: the attitude loops level the *estimated* body, so the true thrust leans that much the
        #: other way, and the rate integrators wind up against it on the ground
        self.lean_x = self.lean_y = 0.0

    def step(
        self, dt: float, cax: float, cay: float, caz: float, cyawrate: float, wn: float, we: float, wd: float
    ) -> None:
        """Advance ``dt`` seconds under commanded acceleration (NED, net of gravity) and yaw rate."""
        if not self.motors:
            cax = cay = 0.0
            caz = GRAVITY  # free fall
            cyawrate = 0.0
        czt = caz
        if self.delay_x:  # the attitude loops' delay: act on the command of delay_steps ago
            i = self.delay_i
            dx, dy, dz = self.delay_x, self.delay_y, self.delay_z
            dx[i], cax = cax, dx[i]
            dy[i], cay = cay, dy[i]
            dz[i], czt = caz, dz[i]
            self.delay_i = i + 1 if i + 1 < len(dx) else 0
        self.cax, self.cay, self.caz, self.czt = cax, cay, caz, czt
        k = dt / self.tau_tilt
        self.ax += (cax - self.ax) * k
        self.ay += (cay - self.ay) * k
        self.azt += (czt - self.azt) * k
        self.az += (caz - self.az) * (dt / TAU_THRUST)
        rx, ry, rz = self.vx - wn, self.vy - we, self.vz - wd
        drag = self.kl + self.kq * math.sqrt(rx * rx + ry * ry)
        lift = GRAVITY - self.az
        fx = self.ax - lift * self.lean_x - drag * rx
        fy = self.ay - lift * self.lean_y - drag * ry
        fz = self.az - DRAG_VERTICAL * rz
        if self.kick_s >= 0.0:
            r = self.kick_s / KICK_TAU
            h = r * r * math.exp(2.0 * (1.0 - r))
            self.kx, self.ky = self.kick_x * h, self.kick_y * h
            fx += self.kx
            fy += self.ky
            self.kick_s += dt
            if self.kick_s > KICK_END:
                self.kick_s = -1.0
                self.kx = self.ky = 0.0
        if self.on_ground:
            if fz >= -self.liftoff_acc:  # not enough thrust to leave the ground: no motion
                self.vx = self.vy = self.vz = 0.0
                self.kax = self.kay = self.kaz = 0.0
                self.yawrate = self.yaw_int = self.yaw_torque = 0.0
                if self.windup:
                    self.ax = self.ay = 0.0  # SIH's ground holds the body still, here level
                    if self.rate_integrating and self.motors:
                        wx = self.wx + (cax / GRAVITY - self.lean_x) * dt
                        wy = self.wy + (cay / GRAVITY - self.lean_y) * dt
                        w = math.hypot(wx, wy)
                        if w > KICK_WINDUP_MAX:  # the integrators' limit
                            wx, wy = wx * KICK_WINDUP_MAX / w, wy * KICK_WINDUP_MAX / w
                        self.wx, self.wy = wx, wy
                    else:
                        self.wx = self.wy = 0.0
                return
            self.on_ground = False
            if self.windup:  # let go with the integrators wound up: the kick (KICK_GAIN)
                self.kick_s = 0.0
                self.kick_x, self.kick_y = KICK_GAIN * GRAVITY * self.wx, KICK_GAIN * GRAVITY * self.wy
                self.wx = self.wy = 0.0
        self.kax, self.kay, self.kaz = fx, fy, fz
        self.vx += fx * dt
        self.vy += fy * dt
        self.vz += fz * dt
        self.x += self.vx * dt
        self.y += self.vy * dt
        self.z += self.vz * dt
        g = self.yaw_rate_gains
        if not self.motors and g is not None:  # disarmed: no rate loop, no torque
            self.yaw_int = self.yaw_torque = 0.0
            self.yawrate -= YAW_DAMPING * self.yawrate * dt
        elif g is None:
            self.yawrate += (cyawrate - self.yawrate) * (dt / TAU_YAW_GAZEBO)
        else:
            # RateControl::update (yaw): P on the rate error plus its integral, then SIH's motors
            # and yaw moment against its angular damping
            e = cyawrate - self.yawrate
            u = g.p * e + self.yaw_int
            # the control allocation (sequential desaturation) gives in on yaw first: the rotors'
            # differential stays within the collective thrust's headroom, and the rate loop's
            # integral stops growing into a saturated direction
            collective = (GRAVITY - self.az) * HOVER_THRUST / GRAVITY
            umax = min(collective, 1.0 - collective)
            if u > umax:
                u = umax
                e = min(e, 0.0)
            elif u < -umax:
                u = -umax
                e = max(e, 0.0)
            f = e / I_FACTOR_RATE
            f = 1.0 - f * f
            if f > 0.0:
                i = self.yaw_int + f * g.i * e * dt
                self.yaw_int = g.int_lim if i > g.int_lim else (-g.int_lim if i < -g.int_lim else i)
            self.yaw_torque += (u - self.yaw_torque) * (dt / TAU_THRUST)
            self.yawrate += (YAW_TORQUE_GAIN * self.yaw_torque - YAW_DAMPING * self.yawrate) * dt
        self.yaw += self.yawrate * dt
        if self.yaw > math.pi:
            self.yaw -= 2 * math.pi
        elif self.yaw < -math.pi:
            self.yaw += 2 * math.pi
        if self.z >= 0.0:
            self.z = 0.0
            if self.vz > 0.0:
                self.vz = 0.0
            self.vx = self.vy = 0.0
            self.on_ground = True

    def tilt(self) -> tuple[float, float]:
        """(roll, pitch) radians of the thrust's direction at this yaw: the horizontal
        acceleration against the vertical one as the attitude loops have it (``azt``)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        lift = GRAVITY - self.azt
        if lift <= 0.1:
            lift = 0.1
        ax, ay = self.ax + self.kx, self.ay + self.ky
        if not self.on_ground:  # the ground holds the body level
            ax -= lift * self.lean_x
            ay -= lift * self.lean_y
        fwd = c * ax + s * ay
        right = -s * ax + c * ay
        return math.atan2(right, lift), -math.atan2(fwd, lift)

    def rates(self) -> tuple[float, float, float]:
        """Body rates (FRD, rad/s) of the attitude ``tilt`` and ``yaw`` describe, as a gyro reads
        them (PX4's ``vehicle_angular_velocity``): the Euler angles' rates, from the rates of the
        first-order responses in ``step``, turned into the body frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        yr = self.yawrate
        dax = (self.cax - self.ax) / self.tau_tilt
        day = (self.cay - self.ay) / self.tau_tilt
        ax, ay = self.ax + self.kx, self.ay + self.ky
        if self.kick_s >= 0.0:  # the lift-off kick's pulse turns the body too
            r = self.kick_s / KICK_TAU
            dh = 2.0 * r * (1.0 - r) / KICK_TAU * math.exp(2.0 * (1.0 - r))
            dax += self.kick_x * dh
            day += self.kick_y * dh
        fwd = c * ax + s * ay
        right = -s * ax + c * ay
        dfwd = c * dax + s * day + yr * right
        dright = -s * dax + c * day - yr * fwd
        lift = GRAVITY - self.azt
        dlift = -(self.czt - self.azt) / self.tau_tilt
        if lift <= 0.1:  # tilt's floor: the angles do not move with it
            lift, dlift = 0.1, 0.0
        roll = math.atan2(right, lift)
        pitch = -math.atan2(fwd, lift)
        droll = (dright * lift - right * dlift) / (right * right + lift * lift)
        dpitch = -(dfwd * lift - fwd * dlift) / (fwd * fwd + lift * lift)
        sr, cr = math.sin(roll), math.cos(roll)
        sp, cp = math.sin(pitch), math.cos(pitch)
        # ZYX Euler angle rates to body rates
        return droll - yr * sp, dpitch * cr + yr * sr * cp, -dpitch * sr + yr * cr * cp
