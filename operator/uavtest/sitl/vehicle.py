"""The simulated PX4 multicopter: commander, navigator, controller and physics, fed by
MAVLink messages and clock ticks, with no I/O (h11 style).

- ``receive(msg)`` handles one inbound message and returns the direct replies (for the link it
  came from); ``advance(until_us)`` runs the simulation up to a vehicle time; ``drain()``
  returns what is to be broadcast on every link (telemetry, status texts).
- Physics at 250 Hz; estimator, wind, land detector, navigator and controller at 50 Hz;
  telemetry on the vehicle clock (``telemetry.Schedule``); PX4 topics to the flight recorder.
- Randomness comes only from ``random.Random`` streams derived from the seed, so the same
  configuration and seed, fed the same messages at the same vehicle times, fly the same
  trajectory bit for bit.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

from uavtest.px4.modes import (
    ARMING_STATE_ARMED,
    ARMING_STATE_DISARMED,
    AUTO_NAV_STATES,
    MANUAL_NAV_STATES,
    NavState,
    base_mode_flags,
    custom_mode,
    nav_state_from_custom_mode,
    split_custom_mode,
)
from uavtest.sitl import mav
from uavtest.sitl import ulog_topics as topics
from uavtest.sitl.controller import Controller, Goal, GoalKind, Limits
from uavtest.sitl.estimator import Estimator
from uavtest.sitl.geo import Projection
from uavtest.sitl.mav import LandedState, MavCmd, MavResult, MavSeverity, MavState, Msg, ParamType
from uavtest.sitl.mission import NavItem
from uavtest.sitl.navigator import EventKind, Navigator, State
from uavtest.sitl.params import ParamStore
from uavtest.sitl.physics import GRAVITY, Body, WindModel, World
from uavtest.sitl.protocols import MissionProtocol, ParamProtocol
from uavtest.sitl.recorder import FlightRecorder, LogSink
from uavtest.sitl.telemetry import MESSAGE_IDS, Schedule
from uavtest.sitl.ulog_writer import LOG_LEVEL
from uavtest.spec.models import Home, Obstacle, UavTestSpec, Wind

__all__ = ["STEP_US", "SimConfig", "Vehicle"]

STEP_US = 4_000  # 250 Hz physics
CONTROL_EVERY = 5  # 50 Hz control
CONTROL_DT = STEP_US * CONTROL_EVERY / 1e6
READY_US = 1_500_000  # estimator converged, home set
SW_VERSION = 0x010F0000  # reported as PX4 v1.15.0 compatible
TAKEOFF_DETECT_S = 0.8  # into the takeoff ramp, PX4's land detector reports the takeoff

_NEEDS_FIX = frozenset({"GLOBAL_POSITION_INT", "HOME_POSITION"})  # PX4 sends them once it has a fix

# vehicle_status.latest_(dis)arming_reason
REASON_EXTERNAL = 4
REASON_MISSION_START = 5
REASON_AUTO_DISARM_LAND = 7
REASON_AUTO_DISARM_PREFLIGHT = 8
REASON_FAILURE_DETECTOR = 11


@dataclass(frozen=True)
class SimConfig:
    """What the simulator takes from a test: home, obstacles, wind, boot parameters, seed."""

    home: Home = field(default_factory=Home)
    obstacles: Sequence[Obstacle] = ()
    wind: Wind = field(default_factory=Wind)
    params: Mapping[str, int | float] = field(default_factory=dict)
    seed: int = 0

    @classmethod
    def from_spec(
        cls, spec: UavTestSpec, seed: int, params: Mapping[str, int | float] | None = None
    ) -> SimConfig:
        return cls(
            home=spec.world.home,
            obstacles=tuple(spec.world.obstacles),
            wind=spec.world.wind,
            params=dict(spec.vehicle.params if params is None else params),
            seed=seed,
        )


class Vehicle:
    def __init__(self, config: SimConfig, sink: LogSink | None = None) -> None:
        self.config = config
        seed = config.seed
        variation = random.Random(f"{seed}:vehicle")
        self.params = ParamStore(config.params)
        self.proj = Projection(config.home.lat, config.home.lon)
        self.home_alt = config.home.alt
        self.body = Body(
            tau_tilt=0.12 * variation.uniform(0.9, 1.1), drag_scale=variation.uniform(0.93, 1.07)
        )
        self.world = World(config.obstacles)
        self.wind = WindModel(config.wind, random.Random(f"{seed}:wind"))
        self.est = Estimator(random.Random(f"{seed}:estimator"))
        self._land_jitter = variation.uniform(0.0, 0.8)
        self.limits = Limits.of(self.params)
        self.ctrl = Controller(self.limits, yaw_rate_scale=variation.uniform(0.6, 1.0))
        self.nav = Navigator(self.params, self.proj, self.home_alt, random.Random(f"{seed}:navigator"))
        self.param_proto = ParamProtocol(self.params)
        self.mission_proto = MissionProtocol()
        self.schedule = Schedule()
        self.recorder = FlightRecorder(
            sink,
            {
                "sys_name": "PX4",
                "ver_hw": "UAVTEST_SITL",
                "ver_sw": "uavtest-sitl",
                "ver_sw_release": SW_VERSION,
                "sys_os_name": "uavtest",
                "sys_toolchain": "CPython",
                "time_ref_utc": 0,
                "uavtest_seed": seed,
            },
        )
        # clock
        self.time_us = 0
        self._next_us = STEP_US
        self._tick = 0
        self._cmd = (0.0, 0.0, GRAVITY, 0.0)
        self._out: list[Msg] = []
        # commander state
        self.armed = False
        self.armed_at_us = 0
        self.nav_state = NavState.AUTO_LOITER
        self.user_nav_state = NavState.AUTO_LOITER
        self.nav_state_us = 0
        self.arming_reason = 0
        self.disarming_reason = 0
        self.landed = True
        self.ground_contact = True
        self.maybe_landed = True
        self.landed_at_us = 0
        self.takeoff_us = 0
        self._ground_since: int | None = None
        self.crashed = False
        self.crash_obstacle: int | None = None
        self.failsafe = False
        self.gcs_lost = False
        self.ready = False
        self.home_set = False
        self.home = (0.0, 0.0, 0.0, config.home.lat, config.home.lon, config.home.alt, 0.0)
        self._home_count = 0
        self._last_gcs_us: int | None = None
        self._sticks = (0.0, 0.0, 0.5, 0.0)
        self._sticks_us: int | None = None
        self._close_log = False
        self.goal = Goal()
        self.st = State()
        self._status_dirty = True
        self.recorder.start(0, self.params)
        self._estimate()
        self._control_tick(0)

    # ------------------------------------------------------------------ public surface

    def heartbeat(self) -> Msg:
        """A HEARTBEAT for now (the edge repeats it while a lockstep client is silent)."""
        return self._telemetry("HEARTBEAT", self.time_us)

    def drain(self) -> list[Msg]:
        out, self._out = self._out, []
        return out

    def advance(self, until_us: int) -> list[Msg]:
        """Simulate up to vehicle time ``until_us``; returns the broadcast messages due meanwhile."""
        body = self.body
        wind = self.wind
        world = self.world
        dt = STEP_US / 1e6
        while self._next_us <= until_us:
            t = self._next_us
            ax, ay, az, yr = self._cmd
            body.step(dt, ax, ay, az, yr, wind.n, wind.e, wind.d)
            if world.near and not self.crashed and not body.on_ground:
                hit = world.hit(body.x, body.y, body.z)
                if hit is not None:
                    self._crash(t, hit.index)
            self._tick += 1
            self._next_us = t + STEP_US
            if self._tick % CONTROL_EVERY == 0:
                self._control_tick(t)
        if until_us > self.time_us:
            self.time_us = until_us
        return self.drain()

    def fly_until(self, condition: Callable[[Vehicle], bool], within_us: int) -> None:
        """Advance in 20 ms slices until ``condition(self)`` holds, at most ``within_us`` (tests, tools)."""
        limit_us = self.time_us + within_us
        while self.time_us < limit_us and not condition(self):
            self.advance(self.time_us + 20_000)
            self._out.clear()

    def load_mission(self, items: list[NavItem]) -> None:
        """Install a mission directly (in-process use; MAVLink clients upload it)."""
        self.mission_proto.items = list(items)
        self.nav.set_mission(items)
        self._log_mission_result()

    def receive(self, msg: Msg) -> list[Msg]:
        """Handle one message from a client; returns the replies to send back to it."""
        name = msg.name
        t = self.time_us
        if name == "HEARTBEAT":
            if msg.get("type") == mav.MAV_TYPE_GCS:
                self._last_gcs_us = t
                if self.gcs_lost:
                    self.gcs_lost = False
                    self._text(MavSeverity.INFO, "Data link regained")
            return []
        if name in ("COMMAND_LONG", "COMMAND_INT"):
            return self._command(msg)
        if name == "MANUAL_CONTROL":
            self._manual_control(msg)
            return []
        if name == "SET_MODE":
            if msg.get("target_system", 1) in (0, mav.SYSTEM_ID):
                main, sub = split_custom_mode(int(msg.get("custom_mode", 0)))
                self._set_mode(nav_state_from_custom_mode(main, sub))
            return []
        if name == "TIMESYNC":
            if int(msg.get("tc1", 0)) == 0:
                return [Msg("TIMESYNC", {"tc1": t * 1000, "ts1": int(msg.get("ts1", 0))})]
            return []
        if name == "MISSION_SET_CURRENT":
            self.nav.set_current(int(msg.get("seq", 0)))
            self._drain_nav_events()
            return []
        replies = self.param_proto.handle(msg)
        if replies is not None:
            self._params_changed()
            return replies
        replies = self.mission_proto.handle(msg, t, self.nav.current)
        if replies is not None:
            if self.mission_proto.installed is not None:
                self.nav.set_mission(self.mission_proto.installed)
                self.mission_proto.installed = None
                self._drain_nav_events()
                self._log_mission_result()
            return replies
        return []

    # ------------------------------------------------------------------ estimate

    def _estimate(self) -> None:
        b, e, st = self.body, self.est, self.st
        st.x, st.y, st.z = b.x + e.ex, b.y + e.ey, b.z + e.ez
        st.yaw = b.yaw + e.eh
        st.landed = self.landed

    # ------------------------------------------------------------------ 50 Hz

    def _control_tick(self, t: int) -> None:
        dt = CONTROL_DT
        self.est.update(dt)
        self.wind.update(dt)
        if self._tick % (CONTROL_EVERY * 10) == 0:
            self.world.refresh_near(self.body.x, self.body.y)
        self._estimate()
        self._commander(t)
        goal = self._goal_for(t)
        self.goal = goal
        b, e, st = self.body, self.est, self.st
        if self.armed and not self.crashed:
            self._cmd = self.ctrl.update(
                dt, goal, st.x, st.y, st.z, b.vx + e.evx, b.vy + e.evy, b.vz + e.evz, st.yaw
            )
            b.motors = True
        else:
            self._cmd = (0.0, 0.0, GRAVITY, 0.0)
            b.motors = False
            self.ctrl.reset(st.x, st.y, st.z, 0.0, 0.0, 0.0, st.yaw)
        self._drain_nav_events()
        for name in self.schedule.due(t):
            if self.ready or name not in _NEEDS_FIX:
                self._out.append(self._telemetry(name, t))
        self._log(t)
        if self._close_log:
            self._close_log = False
            self.recorder.stop()

    def _goal_for(self, t: int) -> Goal:
        if not self.armed or self.crashed:
            return Goal(GoalKind.IDLE)
        if t - self.armed_at_us < self.params["COM_SPOOLUP_TIME"] * 1e6 and self.landed:
            return Goal(GoalKind.IDLE)
        ns = self.nav_state
        if ns in MANUAL_NAV_STATES:
            kind = {
                NavState.POSCTL: GoalKind.VELOCITY,
                NavState.ALTCTL: GoalKind.ALTITUDE,
            }.get(ns, GoalKind.ATTITUDE)
            if (
                self.landed
                and self._sticks[2] <= 0.5 + self.params["MPC_HOLD_DZ"] / 2
                and kind != GoalKind.ATTITUDE
            ):
                return Goal(GoalKind.IDLE)
            return Goal(kind, sticks=self._sticks)
        return self.nav.update(self.st, t / 1e6)

    # ------------------------------------------------------------------ commander

    def _commander(self, t: int) -> None:
        p = self.params
        b = self.body
        if not self.ready and t >= READY_US:
            self.ready = True
            self._set_home(t)
            self._text(MavSeverity.INFO, "Ready for takeoff!")
        if self.armed:
            if self.landed:
                airborne = not b.on_ground and b.z < -0.15
                ramp_done = self.goal.kind is GoalKind.TAKEOFF and self.ctrl.ramp >= TAKEOFF_DETECT_S
                if airborne or ramp_done:
                    self.landed = self.ground_contact = self.maybe_landed = False
                    self.takeoff_us = t
                    self._ground_since = None
                    self._status_dirty = True
                    self._text(MavSeverity.INFO, "Takeoff detected")
            elif b.on_ground and self._descent_commanded():
                if self._ground_since is None:
                    self._ground_since = t
                on = (t - self._ground_since) / 1e6
                self.ground_contact = on >= 0.3
                self.maybe_landed = on >= 1.0 + self._land_jitter
                if on >= 1.0 + self._land_jitter + p["LNDMC_TRIG_TIME"]:
                    self.landed = True
                    self.landed_at_us = t
                    self._status_dirty = True
                    self._text(MavSeverity.INFO, "Landing detected")
            else:
                self._ground_since = None
                self.ground_contact = self.maybe_landed = False
        elif not self.landed and b.on_ground:
            self.landed = self.ground_contact = self.maybe_landed = True
            self.landed_at_us = t
            self._status_dirty = True
        if self.st.landed != self.landed:  # tell clients at once, not at the next 2 Hz slot
            self.st.landed = self.landed
            self._out.append(self._telemetry("EXTENDED_SYS_STATE", t))
        if not self.armed:
            return
        if self.crashed:
            if b.on_ground:
                self._disarm(t, REASON_FAILURE_DETECTOR, "Disarmed after crash")
            return
        if self.landed:
            if self.takeoff_us > self.armed_at_us:
                if self.nav_state in AUTO_NAV_STATES:
                    self.nav.update(self.st, t / 1e6)  # the navigator sees the landing first (finished)
                    self._drain_nav_events()
                    if self.nav_state == NavState.AUTO_MISSION and self.nav.finished:
                        self._text(MavSeverity.INFO, "Mission finished, landed")
                    self._disarm(t, REASON_AUTO_DISARM_LAND, "Disarmed by landing")
                elif p["COM_DISARM_LAND"] > 0 and t - self.landed_at_us >= p["COM_DISARM_LAND"] * 1e6:
                    self._disarm(t, REASON_AUTO_DISARM_LAND, "Disarmed by landing")
            elif p["COM_DISARM_PRFLT"] > 0 and t - self.armed_at_us >= p["COM_DISARM_PRFLT"] * 1e6:
                self._disarm(t, REASON_AUTO_DISARM_PREFLIGHT, "Disarmed by auto preflight disarming")
            return
        # failsafes in the air
        if (
            int(p["NAV_DLL_ACT"]) > 0
            and self._last_gcs_us is not None
            and not self.gcs_lost
            and t - self._last_gcs_us > p["COM_DL_LOSS_T"] * 1e6
        ):
            self.gcs_lost = True
            self._text(MavSeverity.CRITICAL, "Connection to ground station lost")
            self._failsafe(int(p["NAV_DLL_ACT"]), t)
        if (
            self.nav_state in MANUAL_NAV_STATES
            and self._sticks_us is not None
            and t - self._sticks_us > max(p["COM_RC_LOSS_T"], 0.1) * 1e6
            and int(p["NAV_RCL_ACT"]) > 0
        ):
            self._text(MavSeverity.CRITICAL, "Manual control lost")
            self._sticks_us = None
            self._failsafe(int(p["NAV_RCL_ACT"]), t)

    def _descent_commanded(self) -> bool:
        """PX4's land detector: under climb-rate control, ground contact needs a commanded descent.

        While the takeoff ramp builds up thrust (or any climb is commanded) a vehicle still
        resting on the ground is not landing: PX4 requires the velocity setpoint to point down
        at >= 1.1 LNDMC_Z_VEL_MAX (itself capped at min(MPC_LAND_CRWL, MPC_LAND_SPEED) / 1.2)
        until it is landed. Without climb-rate control (manual/stabilized) thrust alone decides,
        and the body only rests on the ground at low thrust.
        """
        kind = self.goal.kind
        if kind is GoalKind.TAKEOFF:
            return False
        if kind in (GoalKind.ATTITUDE, GoalKind.IDLE):
            return True
        p = self.params
        z_vel_max = min(p["LNDMC_Z_VEL_MAX"], min(p["MPC_LAND_CRWL"], p["MPC_LAND_SPEED"]) / 1.2)
        return self.ctrl.vz >= 1.1 * z_vel_max

    def _failsafe(self, action: int, t: int) -> None:
        """NAV_DLL_ACT / NAV_RCL_ACT: 1 hold, 2 return, 3 land, 5 terminate."""
        target = {1: NavState.AUTO_LOITER, 2: NavState.AUTO_RTL, 3: NavState.AUTO_LAND}.get(action)
        self.failsafe = True
        if action == 5:
            self._text(MavSeverity.CRITICAL, "Failsafe: flight termination")
            self.body.motors = False
            self.crashed = True
            return
        if target is not None:
            self._text(MavSeverity.WARNING, f"Failsafe activated: {target.name.lower().replace('auto_', '')}")
            self._switch(target, t)

    def _set_home(self, t: int) -> None:
        st = self.st
        lat, lon = self.proj.reproject(st.x, st.y)
        self.home = (st.x, st.y, st.z, lat, lon, self.home_alt - st.z, st.yaw)
        self.nav.home = (st.x, st.y, st.z)
        self.home_set = True
        self._home_count += 1
        self.recorder.data(
            "home_position",
            (
                t,
                lat,
                lon,
                self.home_alt - st.z,
                st.x,
                st.y,
                st.z,
                st.yaw,
                True,
                True,
                True,
                False,
                self._home_count,
            ),
        )
        self._out.append(self._home_position(t))

    def _arm(self, t: int, reason: int) -> MavResult:
        if self.armed:
            return MavResult.ACCEPTED
        if not self.ready:
            self._text(MavSeverity.CRITICAL, "Arming denied: system not ready")
            return MavResult.TEMPORARILY_REJECTED
        if self.crashed:
            self._text(MavSeverity.CRITICAL, "Arming denied: vehicle crashed")
            return MavResult.DENIED
        if self.nav_state == NavState.AUTO_MISSION and not self.nav.mission:
            self._text(MavSeverity.CRITICAL, "Arming denied: no valid mission")
            return MavResult.DENIED
        if self.nav_state == NavState.OFFBOARD:
            return MavResult.DENIED
        if not self.recorder.active:
            self.recorder.start(t, self.params)
        self.armed = True
        self.armed_at_us = t
        self.arming_reason = reason
        self.failsafe = False
        self._set_home(t)
        if self.nav_state == NavState.AUTO_MISSION and self.nav.finished:
            self.nav.set_current(0)
        self.nav.enter(self.nav_state, self.st, t / 1e6)
        self.ctrl.reset(self.st.x, self.st.y, self.st.z, 0.0, 0.0, 0.0, self.st.yaw)
        self._status_dirty = True
        self._text(MavSeverity.INFO, "Armed by external command")
        return MavResult.ACCEPTED

    def _disarm(self, t: int, reason: int, text: str) -> None:
        self.armed = False
        self.disarming_reason = reason
        self.body.motors = False
        self._status_dirty = True
        self._text(MavSeverity.INFO, text)
        self._close_log = True

    def _crash(self, t: int, index: int) -> None:
        b = self.body
        self.crashed = True
        self.crash_obstacle = index
        self.failsafe = True
        b.vx = b.vy = 0.0
        b.ax = b.ay = 0.0
        b.motors = False
        self._cmd = (0.0, 0.0, GRAVITY, 0.0)
        self._status_dirty = True
        self._text(MavSeverity.CRITICAL, f"crash: collided with obstacle {index}")

    def _set_mode(self, ns: NavState | None) -> MavResult:
        if ns is None or ns == NavState.OFFBOARD:
            return MavResult.DENIED
        if self.crashed:
            return MavResult.DENIED
        if ns == NavState.AUTO_MISSION and not self.nav.mission:
            self._text(MavSeverity.CRITICAL, "Mode not available: no valid mission")
            return MavResult.TEMPORARILY_REJECTED
        self.user_nav_state = ns
        self.failsafe = False
        self._switch(ns, self.time_us)
        return MavResult.ACCEPTED

    def _switch(
        self, ns: NavState, t: int, *, target_alt: float | None = None, hold_z: float | None = None
    ) -> None:
        if ns == self.nav_state and target_alt is None:
            return
        if ns == NavState.AUTO_MISSION and self.landed and self.nav.finished:
            self.nav.set_current(0)
        self.nav_state = ns
        self.nav_state_us = t
        self.nav.enter(ns, self.st, t / 1e6, target_alt=target_alt, hold_z=hold_z)
        b, e, st = self.body, self.est, self.st
        self.ctrl.reset(st.x, st.y, st.z, b.vx + e.evx, b.vy + e.evy, b.vz + e.evz, st.yaw)
        self._status_dirty = True

    def _manual_control(self, msg: Msg) -> None:
        t = self.time_us
        # PX4's MANUAL_CONTROL: x pitch, y roll, r yaw in [-1000, 1000], z thrust in [0, 1000]
        x = max(-1.0, min(1.0, float(msg.get("x", 0)) / 1000.0))
        y = max(-1.0, min(1.0, float(msg.get("y", 0)) / 1000.0))
        z = max(0.0, min(1.0, float(msg.get("z", 500)) / 1000.0))
        r = max(-1.0, min(1.0, float(msg.get("r", 0)) / 1000.0))
        moving = (x, y, z, r) != self._sticks
        self._sticks = (x, y, z, r)
        self._sticks_us = t
        self.recorder.data(
            "manual_control_setpoint",
            (t, t, True, 2, y, x, r, z * 2.0 - 1.0, 0.0, 0.0, 0.0, moving, int(msg.get("buttons", 0))),
        )

    def _params_changed(self) -> None:
        for name in self.param_proto.changed:
            self.recorder.param(name, self.params.type_of(name) == ParamType.INT32, self.params[name])
        self.param_proto.changed.clear()
        self.limits = Limits.of(self.params)
        self.ctrl.lim = self.limits

    # ------------------------------------------------------------------ commands

    def _command(self, msg: Msg) -> list[Msg]:
        f = msg.fields
        if int(f.get("target_system", 0)) not in (0, mav.SYSTEM_ID):
            return []
        t = self.time_us
        cmd = int(f.get("command", 0))
        p1, p2, p3, p4 = (float(f.get(k, 0.0)) for k in ("param1", "param2", "param3", "param4"))
        if msg.name == "COMMAND_INT":
            p5, p6, p7 = int(f.get("x", 0)) / 1e7, int(f.get("y", 0)) / 1e7, float(f.get("z", 0.0))
        else:
            p5, p6, p7 = float(f.get("param5", 0.0)), float(f.get("param6", 0.0)), float(f.get("param7", 0.0))
        self.recorder.data(
            "vehicle_command",
            topics.command(
                t,
                cmd,
                (p1, p2, p3, p4, p5, p6, p7),
                (msg.sysid, msg.compid),
                (int(f.get("target_system", 0)), int(f.get("target_component", 0))),
                True,
            ),
        )
        extra: list[Msg] = []
        if cmd == MavCmd.COMPONENT_ARM_DISARM:
            if p1 >= 0.5:
                result = self._arm(t, REASON_EXTERNAL)
            elif self.landed or round(p2) == mav.FORCE_DISARM_MAGIC or not self.armed:
                if self.armed:
                    self._disarm(t, REASON_EXTERNAL, "Disarmed by external command")
                result = MavResult.ACCEPTED
            else:
                self._text(MavSeverity.CRITICAL, "Disarming denied: not landed")
                result = MavResult.DENIED
        elif cmd == MavCmd.DO_SET_MODE:
            if int(p1) & 1:
                result = self._set_mode(nav_state_from_custom_mode(int(p2), int(p3)))
            else:
                result = MavResult.DENIED
        elif cmd == MavCmd.NAV_TAKEOFF:
            if self.crashed:
                result = MavResult.DENIED
            else:
                alt = p7 - self.home[5] + self.home[2] if math.isfinite(p7) else None
                self.user_nav_state = NavState.AUTO_TAKEOFF
                self._switch(NavState.AUTO_TAKEOFF, t, target_alt=alt)
                result = MavResult.ACCEPTED
        elif cmd == MavCmd.NAV_LAND:
            result = self._set_mode(NavState.AUTO_LAND)
        elif cmd == MavCmd.NAV_RETURN_TO_LAUNCH:
            result = self._set_mode(NavState.AUTO_RTL)
        elif cmd == MavCmd.MISSION_START:
            if not self.nav.mission:
                result = MavResult.DENIED
            else:
                first = int(p1)
                if 0 < first < len(self.nav.mission):
                    self.nav.set_current(first)
                result = MavResult.ACCEPTED
                if not self.armed:
                    result = self._arm(t, REASON_MISSION_START)
                if result == MavResult.ACCEPTED:
                    result = self._set_mode(NavState.AUTO_MISSION)
        elif cmd == MavCmd.DO_CHANGE_SPEED:
            if p2 > 0:
                self.nav.speed = p2
            elif p2 == -2:
                self.nav.speed = math.nan
            result = MavResult.ACCEPTED
        elif cmd == MavCmd.SET_MESSAGE_INTERVAL:
            self.schedule.set_interval(int(p1), int(p2), t)
            result = MavResult.ACCEPTED
        elif cmd in (MavCmd.REQUEST_MESSAGE, MavCmd.REQUEST_AUTOPILOT_CAPABILITIES):
            wanted = 148 if cmd == MavCmd.REQUEST_AUTOPILOT_CAPABILITIES else int(p1)
            result = MavResult.ACCEPTED
            if wanted == 148:
                extra.append(self._autopilot_version())
            elif wanted in MESSAGE_IDS and (wanted != 242 or self.home_set):
                extra.append(self._telemetry(MESSAGE_IDS[wanted], t))
            else:
                result = MavResult.UNSUPPORTED
        else:
            result = MavResult.UNSUPPORTED
        self.recorder.data("vehicle_command_ack", (t, cmd, int(result), 0, 0, msg.sysid, msg.compid, True))
        self._drain_nav_events()
        ack = Msg(
            "COMMAND_ACK",
            {
                "command": cmd,
                "result": int(result),
                "progress": 0,
                "result_param2": 0,
                "target_system": msg.sysid,
                "target_component": msg.compid,
            },
        )
        return [ack, *extra]

    # ------------------------------------------------------------------ navigator events

    def _drain_nav_events(self) -> None:
        events = self.nav.events
        if not events:
            return
        self.nav.events = []
        t = self.time_us
        changed = False
        for ev in events:
            if ev.kind is EventKind.REACHED:
                self._out.append(Msg("MISSION_ITEM_REACHED", {"seq": int(ev.value)}))  # type: ignore[arg-type]
                changed = True
            elif ev.kind is EventKind.CURRENT:
                self._out.append(self._telemetry("MISSION_CURRENT", t))
                changed = True
            elif ev.kind is EventKind.FINISHED:
                changed = True
            elif ev.kind is EventKind.TEXT:
                severity, text = ev.value  # type: ignore[misc]
                self._text(severity, text)
            elif ev.kind is EventKind.HOLD and self.nav_state == NavState.AUTO_TAKEOFF:
                self.user_nav_state = NavState.AUTO_LOITER
                self._switch(NavState.AUTO_LOITER, t, hold_z=float(ev.value))  # type: ignore[arg-type]
        if changed:
            self._log_mission_result()

    def _log_mission_result(self) -> None:
        nav = self.nav
        total = len(nav.mission)
        self.recorder.data(
            "mission_result",
            (
                self.time_us,
                0,
                0,
                self._home_count,
                nav.reached,
                min(nav.current, 65535),
                total,
                total > 0,
                False,
                nav.finished,
                False,
                0,
                0,
                0,
                0,
            ),
        )

    def _text(self, severity: int, text: str) -> None:
        self._out.append(
            Msg("STATUSTEXT", {"severity": int(severity), "text": text[:50], "id": 0, "chunk_seq": 0})
        )
        level = LOG_LEVEL["info"]
        if severity <= MavSeverity.CRITICAL:
            level = LOG_LEVEL["emergency"] if severity == MavSeverity.EMERGENCY else ord("2")
        elif severity == MavSeverity.ERROR:
            level = LOG_LEVEL["error"]
        elif severity == MavSeverity.WARNING:
            level = LOG_LEVEL["warning"]
        self.recorder.text(level, self.time_us, text)

    # ------------------------------------------------------------------ the log

    def _log(self, t: int) -> None:
        rec = self.recorder
        if not rec.active:
            return
        tick = self._tick
        b, e, st = self.body, self.est, self.st
        rec.data(
            "vehicle_local_position",
            topics.local_position(
                t,
                (st.x, st.y, st.z),
                (b.vx + e.evx, b.vy + e.evy, b.vz + e.evz),
                (b.ax, b.ay, b.az + 0.0),
                st.yaw,
                (self.config.home.lat, self.config.home.lon, self.home_alt),
                0,
                True,
            ),
        )
        if tick % (CONTROL_EVERY * 2) == 0:  # 25 Hz
            roll, pitch = b.tilt()
            q = topics.quaternion(roll, pitch, st.yaw)
            rec.data("vehicle_attitude", (t, t, *q, 0.0, 0.0, 0.0, 0.0, 0))
        if tick % (CONTROL_EVERY * 5) == 0:  # 10 Hz
            lat, lon = self.proj.reproject(st.x, st.y)
            alt = self.home_alt - st.z
            rec.data(
                "vehicle_global_position", (t, t, lat, lon, alt, alt, 0.3, 0.4, self.home_alt, True, False)
            )
            g = self.goal
            cx, cy, cz = self.ctrl.px, self.ctrl.py, self.ctrl.pz
            rec.data(
                "trajectory_setpoint",
                (
                    t,
                    cx,
                    cy,
                    cz,
                    self.ctrl.vx,
                    self.ctrl.vy,
                    self.ctrl.vz,
                    self.ctrl.ax,
                    self.ctrl.ay,
                    0.0,
                    self.ctrl.yaw_sp,
                    self.ctrl.yawrate_sp,
                ),
            )
            self._log_setpoint(t, g)
        if self._status_dirty or tick % (CONTROL_EVERY * 50) == 0:  # on change, else 1 Hz
            self._status_dirty = False
            rec.data(
                "vehicle_status",
                (
                    t,
                    self.armed_at_us if self.armed else 0,
                    self.takeoff_us if not self.landed else 0,
                    self.nav_state_us,
                    ARMING_STATE_ARMED if self.armed else ARMING_STATE_DISARMED,
                    self.arming_reason,
                    self.disarming_reason,
                    int(self.user_nav_state),
                    int(self.nav_state),
                    4 if self.crashed else 0,
                    0,
                    1,
                    self.failsafe,
                    self.gcs_lost,
                    mav.MAV_TYPE_QUADROTOR,
                    mav.SYSTEM_ID,
                    mav.COMPONENT_ID,
                    self.ready,
                ),
            )
            rec.data(
                "vehicle_land_detected",
                (
                    t,
                    self.crashed and not b.on_ground and not self.landed,
                    self.ground_contact,
                    self.maybe_landed,
                    self.landed,
                    False,
                    self.goal.kind is GoalKind.LAND,
                    self.landed,
                    abs(b.vz) > 0.25,
                    math.hypot(b.vx, b.vy) > 1.5,
                    True,
                    self.landed,
                ),
            )
            rec.data("actuator_armed", (t, self.armed, False, self.ready, False, False, False))

    def _log_setpoint(self, t: int, g: Goal) -> None:
        kind = {
            GoalKind.POSITION: topics.SETPOINT_TYPE_POSITION,
            GoalKind.TAKEOFF: topics.SETPOINT_TYPE_TAKEOFF,
            GoalKind.LAND: topics.SETPOINT_TYPE_LAND,
            GoalKind.IDLE: topics.SETPOINT_TYPE_IDLE,
        }.get(g.kind)
        if kind is None or not self.armed:
            return
        lat, lon = self.proj.reproject(g.x, g.y)
        speed = g.speed if g.speed == g.speed else self.limits.cruise
        cur = topics.setpoint(
            t, lat, lon, self.home_alt - g.z, g.yaw, kind, self.params["NAV_ACC_RAD"], speed
        )
        self.recorder.data(
            "position_setpoint_triplet", (t, *topics.INVALID_SETPOINT, *cur, *topics.INVALID_SETPOINT)
        )

    # ------------------------------------------------------------------ telemetry

    def _home_position(self, t: int) -> Msg:
        hx, hy, hz, lat, lon, alt, _ = self.home
        return Msg(
            "HOME_POSITION",
            {
                "latitude": round(lat * 1e7),
                "longitude": round(lon * 1e7),
                "altitude": round(alt * 1000),
                "x": hx,
                "y": hy,
                "z": hz,
                "q": [1.0, 0.0, 0.0, 0.0],
                "approach_x": 0.0,
                "approach_y": 0.0,
                "approach_z": 0.0,
                "time_usec": t,
            },
        )

    def _autopilot_version(self) -> Msg:
        # MAV_PROTOCOL_CAPABILITY: MISSION_FLOAT|PARAM_FLOAT|MISSION_INT|COMMAND_INT|PARAM_ENCODE_BYTEWISE|
        # SET_POSITION_TARGET_LOCAL_NED|SET_POSITION_TARGET_GLOBAL_INT|MAVLINK2|MISSION_FENCE|MISSION_RALLY
        caps = 1 | 2 | 4 | 8 | 16 | 128 | 256 | 8192 | 16384 | 32768
        return Msg(
            "AUTOPILOT_VERSION",
            {
                "capabilities": caps,
                "flight_sw_version": SW_VERSION,
                "middleware_sw_version": SW_VERSION,
                "os_sw_version": 0,
                "board_version": 0,
                "flight_custom_version": [0] * 8,
                "middleware_custom_version": [0] * 8,
                "os_custom_version": [0] * 8,
                "vendor_id": 0,
                "product_id": 0,
                "uid": 1 + self.config.seed,
                "uid2": [0] * 18,
            },
        )

    def landed_state(self) -> LandedState:
        if self.landed:
            return LandedState.ON_GROUND
        if self.goal.kind is GoalKind.TAKEOFF:
            return LandedState.TAKEOFF
        if self.goal.kind is GoalKind.LAND:
            return LandedState.LANDING
        return LandedState.IN_AIR

    def _telemetry(self, name: str, t: int) -> Msg:
        b, e, st = self.body, self.est, self.st
        ms = t // 1000
        if name == "LOCAL_POSITION_NED":
            return Msg(
                "LOCAL_POSITION_NED",
                {
                    "time_boot_ms": ms,
                    "x": st.x,
                    "y": st.y,
                    "z": st.z,
                    "vx": b.vx + e.evx,
                    "vy": b.vy + e.evy,
                    "vz": b.vz + e.evz,
                },
            )
        if name == "ATTITUDE":
            roll, pitch = b.tilt()
            return Msg(
                "ATTITUDE",
                {
                    "time_boot_ms": ms,
                    "roll": roll,
                    "pitch": pitch,
                    "yaw": st.yaw,
                    "rollspeed": 0.0,
                    "pitchspeed": 0.0,
                    "yawspeed": b.yawrate,
                },
            )
        if name == "GLOBAL_POSITION_INT":
            lat, lon = self.proj.reproject(st.x, st.y)
            hdg = round(math.degrees(st.yaw) * 100) % 36000
            return Msg(
                "GLOBAL_POSITION_INT",
                {
                    "time_boot_ms": ms,
                    "lat": round(lat * 1e7),
                    "lon": round(lon * 1e7),
                    "alt": round((self.home_alt - st.z) * 1000),
                    "relative_alt": round((self.home[2] - st.z) * 1000),
                    "vx": round(b.vx * 100),
                    "vy": round(b.vy * 100),
                    "vz": round(b.vz * 100),
                    "hdg": hdg,
                },
            )
        if name == "HEARTBEAT":
            if self.crashed:
                state = MavState.EMERGENCY
            elif self.failsafe:
                state = MavState.CRITICAL
            elif self.armed:
                state = MavState.ACTIVE
            else:
                state = MavState.STANDBY if self.ready else MavState.BOOT
            return Msg(
                "HEARTBEAT",
                {
                    "type": mav.MAV_TYPE_QUADROTOR,
                    "autopilot": mav.MAV_AUTOPILOT_PX4,
                    "base_mode": base_mode_flags(self.nav_state, self.armed),
                    "custom_mode": custom_mode(self.nav_state),
                    "system_status": int(state),
                    "mavlink_version": 3,
                },
            )
        if name == "EXTENDED_SYS_STATE":
            return Msg("EXTENDED_SYS_STATE", {"vtol_state": 0, "landed_state": int(self.landed_state())})
        if name == "SYS_STATUS":
            health = mav.SYS_STATUS_SENSORS & ~mav.SYS_STATUS_GPS
            if self.ready:
                health |= mav.SYS_STATUS_GPS | (0 if self.crashed else mav.SYS_STATUS_PREARM_CHECK)
            return Msg(
                "SYS_STATUS",
                {
                    "onboard_control_sensors_present": mav.SYS_STATUS_SENSORS | mav.SYS_STATUS_PREARM_CHECK,
                    "onboard_control_sensors_enabled": mav.SYS_STATUS_SENSORS | mav.SYS_STATUS_PREARM_CHECK,
                    "onboard_control_sensors_health": health,
                    "load": 100,
                    "voltage_battery": 16200,
                    "current_battery": 1000 if self.armed else 100,
                    "battery_remaining": 100,
                    "drop_rate_comm": 0,
                    "errors_comm": 0,
                    "errors_count1": 0,
                    "errors_count2": 0,
                    "errors_count3": 0,
                    "errors_count4": 0,
                },
            )
        if name == "SYSTEM_TIME":
            return Msg("SYSTEM_TIME", {"time_unix_usec": 0, "time_boot_ms": ms})
        if name == "HOME_POSITION":
            return self._home_position(t)
        if name == "MISSION_CURRENT":
            nav = self.nav
            total = len(nav.mission)
            state = (
                1
                if total == 0
                else 5
                if nav.finished
                else 3
                if self.nav_state == NavState.AUTO_MISSION
                else 2
            )
            return Msg(
                "MISSION_CURRENT",
                {
                    "seq": min(nav.current, 65535),
                    "total": total,
                    "mission_state": state,
                    "mission_mode": int(self.nav_state == NavState.AUTO_MISSION),
                },
            )
        if name == "VFR_HUD":
            return Msg(
                "VFR_HUD",
                {
                    "airspeed": math.hypot(b.vx - self.wind.n, b.vy - self.wind.e),
                    "groundspeed": math.hypot(b.vx, b.vy),
                    "heading": round(math.degrees(st.yaw)) % 360,
                    "throttle": 50 if b.motors else 0,
                    "alt": self.home_alt - st.z,
                    "climb": -b.vz,
                },
            )
        if name == "BATTERY_STATUS":
            return Msg(
                "BATTERY_STATUS",
                {
                    "id": 0,
                    "battery_function": 1,
                    "type": 1,
                    "temperature": 32767,
                    "voltages": [16200] + [65535] * 9,
                    "current_battery": 1000 if self.armed else 100,
                    "current_consumed": -1,
                    "energy_consumed": -1,
                    "battery_remaining": 100,
                },
            )
        if name == "GPS_RAW_INT":
            lat, lon = self.proj.reproject(b.x, b.y)
            return Msg(
                "GPS_RAW_INT",
                {
                    "time_usec": t,
                    "fix_type": 3 if self.ready else 0,
                    "lat": round(lat * 1e7),
                    "lon": round(lon * 1e7),
                    "alt": round((self.home_alt - b.z) * 1000),
                    "eph": 70,
                    "epv": 100,
                    "vel": round(math.hypot(b.vx, b.vy) * 100),
                    "cog": 0,
                    "satellites_visible": 12,
                },
            )
        raise KeyError(name)
