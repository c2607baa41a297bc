"""The multicopter Orbit flight task (PX4 v1.15 ``flight_mode_manager/tasks/Orbit/FlightTaskOrbit.cpp``).

Nav state ORBIT (MAV_CMD_DO_ORBIT). PX4 behaviour kept:

- on activation: radius 1 m (``_radius_min``), 1 m/s clockwise, centre at the vehicle;
- the command: param1 radius (sign = direction, positive clockwise; NaN keeps it), param2
  tangential speed (NaN keeps it), param3 yaw behaviour (NaN keeps it), param5/6 centre
  (NaN: keep), param7 altitude AMSL (NaN: keep); a radius outside [1 m, ``MC_ORBIT_RAD_MAX``]
  is refused with "Orbit radius limit exceeded" (PX4 then switches to its failsafe task: the
  built-in vehicle holds where it is);
- speed limited to 10 m/s and to a centripetal acceleration of 2 m/s² (``_sanitizeParams``);
- off the circle (2 m horizontally, ``NAV_MC_ALT_RAD`` vertically) it first flies to the
  closest point of the circle, facing the centre;
- yaw: 0 front to centre (default), 1 initial heading, 2 uncontrolled (kept), 3 tangent,
  4 RC controlled (no sticks here: kept);
- ``status()`` is PX4's ``orbit_status`` (radius signed by direction, centre, altitude).

The built-in position controller follows points, not PX4's velocity feed-forward: on the circle
the task sets a point that runs ahead along the arc (a lead of up to 45 degrees), flown at the
orbit speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from uavtest.sitl.mc_pos_control import Goal, GoalKind

__all__ = ["FlightTaskOrbit", "OrbitStatus"]

RADIUS_MIN = 1.0  # m (_radius_min)
VELOCITY_MAX = 10.0  # m/s (_velocity_max)
ACCELERATION_MAX = 2.0  # m/s^2 (_acceleration_max)
ACCEPTANCE_RADIUS = 2.0  # m (_horizontal_acceptance_radius)

YAW_FRONT_TO_CENTER = 0
YAW_INITIAL_HEADING = 1
YAW_UNCONTROLLED = 2
YAW_FRONT_TANGENT = 3
YAW_RC_CONTROLLED = 4


@dataclass(frozen=True, slots=True)
class OrbitStatus:
    """PX4 orbit_status: radius (negative: counter-clockwise), centre (local), altitude (local z)."""

    radius: float
    x: float
    y: float
    z: float
    yaw_behaviour: int


class FlightTaskOrbit:
    def __init__(self, rad_max: float) -> None:
        self.rad_max = rad_max
        self.radius = RADIUS_MIN
        self.velocity = 1.0
        self.cx = self.cy = self.cz = 0.0
        self.yaw_behaviour = YAW_FRONT_TO_CENTER
        self.initial_heading = 0.0
        self.hold_yaw = 0.0
        self.approach = True

    def activate(self, x: float, y: float, z: float, yaw: float) -> None:
        self.radius = RADIUS_MIN
        self.velocity = 1.0
        self.cx, self.cy, self.cz = x, y, z
        self.initial_heading = self.hold_yaw = yaw
        self.approach = True

    def _sanitize(self, radius: float, velocity: float) -> tuple[float, float]:
        radius = min(max(radius, RADIUS_MIN), self.rad_max)
        velocity = max(-VELOCITY_MAX, min(VELOCITY_MAX, velocity))
        if velocity * velocity >= ACCELERATION_MAX * radius:
            velocity = math.copysign(math.sqrt(ACCELERATION_MAX * radius), velocity)
        return radius, velocity

    def apply_command(
        self,
        params: tuple[float, float, float, float, float | None, float | None, float | None],
        yaw: float,
    ) -> bool:
        """MAV_CMD_DO_ORBIT on the running task (``applyCommandParameters``); params 5-7 come as
        local x, y and z (None: not given). False when the radius is out of range."""
        p1, p2, p3, _, x, y, z = params
        clockwise = self.velocity > 0
        radius = self.radius
        speed = abs(self.velocity)
        if math.isfinite(p1):
            clockwise = p1 > 0
            radius = abs(p1)
        if math.isfinite(p2):
            speed = p2
        ok = RADIUS_MIN <= radius <= self.rad_max
        if ok:
            self.radius, self.velocity = self._sanitize(radius, speed if clockwise else -speed)
        if math.isfinite(p3):
            self.yaw_behaviour = int(p3)
        self.initial_heading = self.hold_yaw = yaw
        if x is not None and y is not None:
            self.cx, self.cy = x, y
        if z is not None:
            self.cz = z
        self.approach = True
        return ok

    def status(self) -> OrbitStatus:
        return OrbitStatus(
            math.copysign(self.radius, self.velocity) if self.velocity else self.radius,
            self.cx,
            self.cy,
            self.cz,
            self.yaw_behaviour,
        )

    def on_circle(self, x: float, y: float, z: float, alt_rad: float) -> bool:
        d = math.hypot(x - self.cx, y - self.cy)
        return abs(d - self.radius) < ACCEPTANCE_RADIUS and abs(z - self.cz) < alt_rad

    def update(self, x: float, y: float, z: float, yaw: float, alt_rad: float, goal: Goal) -> Goal:
        dx, dy = x - self.cx, y - self.cy
        d = math.hypot(dx, dy)
        if self.approach and self.on_circle(x, y, z, alt_rad):
            self.approach = False
        goal.kind, goal.z = GoalKind.POSITION, self.cz
        if self.approach:
            if d > 1e-6:
                goal.x, goal.y = self.cx + dx / d * self.radius, self.cy + dy / d * self.radius
            else:
                goal.x, goal.y = self.cx + self.radius, self.cy
            goal.yaw = math.atan2(-dy, -dx)
            goal.speed = math.nan
            return goal
        v = self.velocity
        phi = math.atan2(dy, dx)
        lead = min(abs(v) * max(1.0, abs(v) / 2.0 + 0.5) / self.radius, math.pi / 4)
        a = phi + math.copysign(lead, v)
        goal.x, goal.y = self.cx + self.radius * math.cos(a), self.cy + self.radius * math.sin(a)
        goal.speed = abs(v)
        b = self.yaw_behaviour
        if b == YAW_INITIAL_HEADING:
            goal.yaw = self.initial_heading
        elif b == YAW_FRONT_TANGENT:
            goal.yaw = math.atan2(dx, -dy) if v > 0 else math.atan2(-dx, dy)
        elif b in (YAW_UNCONTROLLED, YAW_RC_CONTROLLED):
            goal.yaw = self.hold_yaw
        else:
            goal.yaw = math.atan2(-dy, -dx)
        return goal
