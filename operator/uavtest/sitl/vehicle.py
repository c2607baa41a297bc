"""The simulated PX4 multicopter, a thin façade over PX4-named modules, fed by MAVLink messages
and clock ticks, with no I/O (h11 style).

Modules (named like PX4's ``src/modules``): ``simulator_sih`` (physics, wind, obstacles),
``ekf2`` (estimate), ``land_detector``, ``commander`` (state machine, arming checks, failsafe
tables, vehicle command dispatch), ``navigator`` (mission, hold, takeoff, land, return),
``mc_pos_control`` (flight tasks and position control), ``mavlink_streams`` (telemetry
builders) and the ``recorder`` (logger), exchanging ``uorb`` topic dataclasses that the ULog
records as they are.

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
from typing import ClassVar

from uavtest.px4.modes import (
    MANUAL_NAV_STATES,
    NavState,
    nav_state_from_custom_mode,
    split_custom_mode,
)
from uavtest.sitl import mav
from uavtest.sitl import uorb as topics
from uavtest.sitl.collision_prevention import CollisionPrevention, CpParams
from uavtest.sitl.commander.commander import FLOWN_NAV_STATES, Commander
from uavtest.sitl.commander.failure_detector import TUMBLE_RATE
from uavtest.sitl.commander.vehicle_command import MISSION_PLANNER, handle_command, unsupported
from uavtest.sitl.ekf2 import Estimator
from uavtest.sitl.geo import Projection
from uavtest.sitl.land_detector import LandDetector
from uavtest.sitl.local_planner import LocalPlanner, PlannerParams
from uavtest.sitl.manual_control import StickMovement
from uavtest.sitl.mav import LandedState, MavSeverity, Msg, ParamType
from uavtest.sitl.mavlink_ftp import nak
from uavtest.sitl.mavlink_io import custom_mode_name
from uavtest.sitl.mavlink_streams import ORBIT_STATUS_HZ, STREAMS, SW_VERSION, orbit_execution_status
from uavtest.sitl.mc_hover_thrust_estimator import HoverThrustEstimator
from uavtest.sitl.mc_pos_control import IDLE, Controller, Goal, GoalKind, Limits
from uavtest.sitl.mc_rate_control import YawRateGains
from uavtest.sitl.mission import NavItem
from uavtest.sitl.navigator import EventKind, Navigator, State
from uavtest.sitl.offboard import Offboard
from uavtest.sitl.params import ParamStore
from uavtest.sitl.protocols import MissionProtocol, ParamProtocol
from uavtest.sitl.recorder import FlightRecorder, LogSink
from uavtest.sitl.sensor_depth_sim import DepthCamera
from uavtest.sitl.simulation import Simulation
from uavtest.sitl.simulator_sih import (
    ATTITUDE_DELAY,
    DRAG_GAZEBO_IRIS,
    DRAG_LINEAR,
    DRAG_QUADRATIC,
    DRAG_VERTICAL,
    GRAVITY,
    HOVER_THRUST,
    LIFTOFF_ACC_GAZEBO,
    TAU_TILT,
    TAU_TILT_GAZEBO,
    Body,
    WindModel,
    World,
)
from uavtest.sitl.telemetry import MODES, ONBOARD, Schedule
from uavtest.sitl.ulog_writer import LOG_LEVEL
from uavtest.spec.collision_prevention import range_sensor_of
from uavtest.spec.models import Avoidance, Home, Obstacle, RangeSensor, UavTestSpec, Wind

__all__ = ["STEP_US", "SimConfig", "Vehicle"]

STEP_US = 4_000  # 250 Hz physics
CONTROL_EVERY = 5  # 50 Hz control
CONTROL_DT = STEP_US * CONTROL_EVERY / 1e6

_ORBIT_STATUS_EVERY = round(50 / ORBIT_STATUS_HZ) * CONTROL_EVERY  # physics ticks
_ORBIT = NavState.ORBIT  # a module constant: enum attribute lookups cost in the 50 Hz tick
_NEEDS_FIX = frozenset({"GLOBAL_POSITION_INT", "HOME_POSITION"})  # PX4 sends them once it has a fix
_NO_GLOBAL = frozenset({"GLOBAL_POSITION_INT"})  # nor a global position it has lost
_SETPOINT_TYPE = {
    GoalKind.POSITION: topics.SETPOINT_TYPE_POSITION,
    GoalKind.TAKEOFF: topics.SETPOINT_TYPE_TAKEOFF,
    GoalKind.LAND: topics.SETPOINT_TYPE_LAND,
    GoalKind.IDLE: topics.SETPOINT_TYPE_IDLE,
}
#: manual nav state → the flight task's goal kind (attitude for the others)
_MANUAL_GOAL = {NavState.POSCTL: GoalKind.VELOCITY, NavState.ALTCTL: GoalKind.ALTITUDE}
_DESCEND = NavState.DESCEND
#: nav states whose flight task is not the navigator's: the stick modes and Descend
_NOT_NAVIGATOR = frozenset(MANUAL_NAV_STATES) | {_DESCEND}


@dataclass(frozen=True)
class SimConfig:
    """What the simulator takes from a test: home, obstacles, wind, boot parameters, seed."""

    home: Home = field(default_factory=Home)
    obstacles: Sequence[Obstacle] = ()
    wind: Wind = field(default_factory=Wind)
    params: Mapping[str, int | float] = field(default_factory=dict)
    seed: int = 0
    #: what keeps the vehicle off obstacles (``vehicle.avoidance``)
    avoidance: Avoidance = Avoidance.NONE
    #: the simulated obstacle-distance sensor (``vehicle.rangeSensor``; defaults with
    #: collision-prevention), None: no sensor
    range_sensor: RangeSensor | None = None
    #: the host clock (Unix µs) at boot, for SYSTEM_TIME; 0 (1970) keeps a run independent of the date
    utc_boot_us: int = 0
    #: the MAVLink links (name, telemetry mode of ``telemetry.MODES``), each with its own schedule
    links: tuple[tuple[str, str], ...] = (("api", ONBOARD),)

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
            avoidance=spec.vehicle.avoidance,
            range_sensor=range_sensor_of(spec),
        )


def _mm(v: float) -> int | None:
    """``v`` metres in whole millimetres (NaN: None); cheaper than ``round(v, 3)``."""
    return math.floor(v * 1000.0 + 0.5) if v == v else None


def _triplet_key(g: Goal) -> tuple[object, ...]:
    """What position_setpoint_triplet shows of ``g``: its type, target to the millimetre (a
    landing's altitude is the one it carries; NaN as None) and its track start and next waypoint,
    which are set from waypoints or are the one ``NO_TRACK`` / ``NO_NEXT`` tuple. Equal keys, the
    same triplet. Run every control tick: a handful of operations."""
    z = g.alt_amsl if g.alt_amsl == g.alt_amsl else g.z
    return (g.kind, _mm(g.x), _mm(g.y), _mm(z), g.prev, g.next)


def cp_runs(params: ParamStore) -> bool:
    """Whether PX4 v1.15 runs Collision Prevention in position mode: CP_DIST > 0 (``is_active``)
    and the position-mode task that has it, FlightTaskManualPosition (MPC_POS_MODE 0)."""
    return params["CP_DIST"] > 0 and int(params["MPC_POS_MODE"]) == 0


class Vehicle:
    def __init__(self, config: SimConfig, sink: LogSink | None = None) -> None:
        self.config = config
        seed = config.seed
        variation = random.Random(f"{seed}:vehicle")
        # PX4-Avoidance's local planner: the test's avoidance, or COM_OBS_AVOID 1 among its params
        planner = config.avoidance is Avoidance.LOCAL_PLANNER or config.params.get("COM_OBS_AVOID") == 1
        self.params = ParamStore({**config.params, "COM_OBS_AVOID": 1} if planner else config.params)
        self.proj = Projection(config.home.lat, config.home.lon)
        self.home_alt = config.home.alt
        # the local planner models the competition's system under test (PX4 + PX4-Avoidance in
        # Gazebo, iris, not lockstep), calibrated with its tilt response, drag and yaw rate varying
        # from flight to flight; everything else flies PX4 SIH's physics, which its parameters fix
        # (SIH_KDV, ...), and yaws its setpoint at exactly MPC_YAWRAUTO_MAX (PX4 v1.15 SIH: 45
        # degrees/s throughout a turn). The draws are made either way: a seed's others stay
        tilt_scale, drag_scale = variation.uniform(0.9, 1.1), variation.uniform(0.93, 1.07)
        land_jitter = variation.uniform(0.35, 0.75)  # touchdown to PX4's ground-contact conditions, s
        yaw_rate_scale = variation.uniform(0.6, 1.0)
        if not planner:
            tilt_scale = drag_scale = yaw_rate_scale = 1.0
        self.body = Body(
            tau_tilt=(TAU_TILT_GAZEBO if planner else TAU_TILT) * tilt_scale,
            drag_scale=drag_scale,
            drag=DRAG_GAZEBO_IRIS if planner else (DRAG_LINEAR, DRAG_QUADRATIC),
            delay_steps=0 if planner else round(ATTITUDE_DELAY / (STEP_US / 1e6)),
            yaw_rate_gains=None if planner else YawRateGains.of(self.params),
            liftoff_acc=LIFTOFF_ACC_GAZEBO if planner else 0.0,
            windup=not planner,
        )
        self.world = World(config.obstacles)
        self.wind = WindModel(config.wind, random.Random(f"{seed}:wind"))
        self.est = Estimator(
            random.Random(f"{seed}:estimator"),
            random.Random(f"{seed}:estimator-z"),
            random.Random(f"{seed}:estimator-heading"),
            random.Random(f"{seed}:estimator-ground"),
            random.Random(f"{seed}:estimator-height"),
            random.Random(f"{seed}:estimator-tilt"),
        )
        if planner:
            self.est.gazebo_system()
        # battery, GPS, failure injection / detection: one attribute (CPython 3.11 specialises
        # self.x loads only while an instance has at most 30 attributes -- keep Vehicle below)
        self.sim = Simulation(self.params, seed, config.range_sensor)
        if not planner:
            self.sim.hover_thrust = HoverThrustEstimator(self.params)
        self.limits = Limits.of(self.params)
        self.ctrl = Controller(
            self.limits, yaw_rate_scale=yaw_rate_scale, px4_yaw=not planner, px4_vertical=not planner
        )
        self.land = LandDetector(self.params, self.ctrl, land_jitter, self.est)
        self._land_logged = self.land.state()  # what vehicle_land_detected last said in the log
        self._triplet_logged: tuple[object, ...] = ()  # the goal position_setpoint_triplet last showed
        self.nav = Navigator(self.params, self.proj, self.home_alt, random.Random(f"{seed}:navigator"))
        if planner:  # PX4-Avoidance's local planner flies the auto modes' waypoints (COM_OBS_AVOID 1)
            camera = DepthCamera(self.world, random.Random(f"{seed}:depth"))
            cruise = PlannerParams(cruise=self.params["MPC_XY_CRUISE"])
            self.sim.planner = LocalPlanner(camera, random.Random(f"{seed}:local_planner"), cruise)
            self.nav.yaw_acceptance = False
        self.param_proto = ParamProtocol(self.params)
        self.mission_proto = MissionProtocol()
        self.link_names = [name for name, _ in config.links]
        self.schedules = [Schedule(MODES[mode]) for _, mode in config.links]
        #: links that stream telemetry (the edge turns a quiet GCS link on once a station speaks)
        self.streaming = [True] * len(self.schedules)
        self.rx_link = 0  # the link of the message being handled (SET_MESSAGE_INTERVAL applies to it)
        self._ftp_said = False  # "MAVLink FTP not supported" sent
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
        self._logged_rates = (0, 0.0, 0.0, 0.0)  # (t us, p, q, r) of the last vehicle_angular_velocity
        self._text_id = 0  # STATUSTEXT.id of the last chunked text
        self._cmd = IDLE
        # broadcast messages (every link) are Msg; with several links, one link's telemetry is
        # (link index, Msg) in the same list, so every link sees its messages in order
        self._out: list[Msg | tuple[int, Msg]] = []  # type: ignore[assignment]
        self.goal = Goal()
        self.st = State()
        self.offboard = Offboard(self)
        self.commander = Commander(self)
        self.stick_movement = StickMovement()  # PX4's ManualControl: sticks_moving
        self.recorder.start(0, self.params)
        self._setup_collision_prevention()
        self._estimate()
        self._control_tick(0)

    # ------------------------------------------------------------------ module state, read-only

    armed = property(lambda self: self.commander.armed)
    armed_at_us = property(lambda self: self.commander.armed_at_us)
    nav_state = property(lambda self: self.commander.nav_state)
    user_nav_state = property(lambda self: self.commander.user_nav_state)
    crashed = property(lambda self: self.commander.crashed)
    crash_obstacle = property(lambda self: self.commander.crash_obstacle)
    failsafe = property(lambda self: self.commander.failsafe)
    gcs_lost = property(lambda self: self.commander.gcs_lost)
    ready = property(lambda self: self.commander.ready)
    home_set = property(lambda self: self.commander.home_set)
    home = property(lambda self: self.commander.home)
    battery = property(lambda self: self.sim.battery)
    gps = property(lambda self: self.sim.gps)
    failure_injector = property(lambda self: self.sim.failure_injector)
    failure_detector = property(lambda self: self.sim.failure_detector)

    @property
    def global_position_valid(self) -> bool:
        """EKF2's global position (invalid after dead reckoning without GPS for EKF2_NOAID_TOUT)."""
        return self._global_valid(self.time_us)

    def _global_valid(self, t: int) -> bool:
        return self.sim.gps.position_valid(t, self.params["EKF2_NOAID_TOUT"])

    @property
    def landed(self) -> bool:
        return self.land.landed

    @property
    def landed_at_us(self) -> int:
        return self.land.landed_at_us

    @property
    def takeoff_us(self) -> int:
        return self.land.takeoff_us

    @property
    def ground_contact(self) -> bool:
        return self.land.ground_contact

    @property
    def maybe_landed(self) -> bool:
        return self.land.maybe_landed

    # ------------------------------------------------------------------ public surface

    def heartbeat(self) -> Msg:
        """A HEARTBEAT for now (the edge repeats it while a lockstep client is silent)."""
        return STREAMS["HEARTBEAT"](self, self.time_us)

    @property
    def schedule(self) -> Schedule:
        """The telemetry schedule of the link the message being handled came from."""
        return self.schedules[self.rx_link]

    def drain(self) -> list[Msg]:
        """The messages for the first link (broadcasts and its telemetry); see ``drain_links``."""
        out, self._out = self._out, []
        if len(self.schedules) == 1:
            return out  # type: ignore[return-value]
        return [m if isinstance(m, Msg) else m[1] for m in out if isinstance(m, Msg) or m[0] == 0]

    def drain_links(self) -> list[list[Msg]]:
        """The messages for each link, in link order."""
        out, self._out = self._out, []
        per: list[list[Msg]] = [[] for _ in self.schedules]
        for m in out:
            if isinstance(m, Msg):
                for lst in per:
                    lst.append(m)
            else:
                per[m[0]].append(m[1])
        return per

    def advance(self, until_us: int, *, drain: bool = True) -> list[Msg]:
        """Simulate up to vehicle time ``until_us``; returns the first link's messages due
        meanwhile (``drain=False``: kept for ``drain_links``)."""
        body = self.body
        wind = self.wind
        world = self.world
        commander = self.commander
        dt = STEP_US / 1e6
        while self._next_us <= until_us:
            t = self._next_us
            ax, ay, az, yr = self._cmd
            body.step(dt, ax, ay, az, yr, wind.n, wind.e, wind.d)
            if world.near and not commander.crashed and not body.on_ground:
                hit = world.hit(body.x, body.y, body.z)
                if hit is not None:
                    commander.crash(t, hit.index)
            self._tick += 1
            self._next_us = t + STEP_US
            if self._tick % CONTROL_EVERY == 0:
                # what the tick logs and announces (mission_result, STATUSTEXT, navigator events)
                # carries the tick's own time, as PX4 stamps each publication, not the time the
                # caller last advanced to: the flight and its log do not depend on the slices
                # the clock is granted in
                self.time_us = t
                self._control_tick(t)
        if until_us > self.time_us:
            self.time_us = until_us
        return self.drain() if drain else []

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

    def receive(self, msg: Msg, link: int = 0) -> list[Msg]:
        """Handle one message from a client on link ``link``; returns the replies to send back to it."""
        self.rx_link = link
        handler = self._RECEIVE.get(msg.name)
        if handler is not None:
            return handler(self, msg)
        replies = self.param_proto.handle(msg)
        if replies is not None:
            self._params_changed()
            return replies
        replies = self.mission_proto.handle(msg, self.time_us, self.nav.current)
        if replies is not None:
            if self.mission_proto.installed is not None:
                self.nav.set_mission(self.mission_proto.installed, self.time_us / 1e6)
                self.mission_proto.installed = None
                self.drain_nav_events()
                self._log_mission_result()
            self._install_fence_rally()
            return replies
        return []

    def _install_fence_rally(self) -> None:
        """A fence or rally plan just uploaded / cleared goes to the navigator (PX4: dataman)."""
        proto = self.mission_proto
        if proto.fence_installed is not None:
            c = self.commander
            flying = c.armed and not self.land.landed and int(self.params["GF_ACTION"]) != 0
            self.nav.set_fence(proto.fence_installed, (self.st.x, self.st.y) if flying else None)
            proto.fence_installed = None
            self.drain_nav_events()
            self._log_mission_result()
        if proto.rally_installed is not None:
            self.nav.set_rally(proto.rally_installed)
            proto.rally_installed = None

    def landed_state(self) -> LandedState:
        if self.land.landed:
            return LandedState.ON_GROUND
        if self.goal.kind is GoalKind.TAKEOFF:
            return LandedState.TAKEOFF
        if self.goal.kind is GoalKind.LAND:
            return LandedState.LANDING
        return LandedState.IN_AIR

    # ------------------------------------------------------------------ inbound messages

    def _on_heartbeat(self, msg: Msg) -> list[Msg]:
        if msg.get("type") == mav.MAV_TYPE_GCS:
            self.commander.gcs_heartbeat(self.time_us)
        return []

    def _on_command(self, msg: Msg) -> list[Msg]:
        return handle_command(self, msg)

    def _on_manual_control(self, msg: Msg) -> list[Msg]:
        t = self.time_us
        # PX4's MANUAL_CONTROL: x pitch, y roll, r yaw in [-1000, 1000], z thrust in [0, 1000]
        x = max(-1.0, min(1.0, float(msg.get("x", 0)) / 1000.0))
        y = max(-1.0, min(1.0, float(msg.get("y", 0)) / 1000.0))
        z = max(0.0, min(1.0, float(msg.get("z", 500)) / 1000.0))
        r = max(-1.0, min(1.0, float(msg.get("r", 0)) / 1000.0))
        # manual_control_setpoint: roll y, pitch x, yaw r, throttle 2 z - 1, each in [-1, 1]
        p = self.params
        moving = self.stick_movement.update(
            t, (y, x, r, z * 2.0 - 1.0), p["COM_RC_STICK_OV"], max(p["COM_RC_LOSS_T"], 0.1)
        )
        self.commander.manual_control(t, (x, y, z, r), moving)
        self.recorder.data(
            topics.ManualControlSetpoint(
                t, t, True, 2, y, x, r, z * 2.0 - 1.0, 0.0, 0.0, 0.0, moving, int(msg.get("buttons", 0))
            )
        )
        return []

    def _on_set_mode(self, msg: Msg) -> list[Msg]:
        if msg.get("target_system", 1) in (0, mav.SYSTEM_ID):
            main, sub = split_custom_mode(int(msg.get("custom_mode", 0)))
            ns = nav_state_from_custom_mode(main, sub)
            if ns is None or ns not in FLOWN_NAV_STATES:
                unsupported(self, f"Mode {custom_mode_name(main, sub)}")
            else:  # mavlink_receiver: a DO_SET_MODE from the message's sender
                self.commander.set_mode(ns, announce=msg.compid == MISSION_PLANNER)
        return []

    def _on_timesync(self, msg: Msg) -> list[Msg]:
        if int(msg.get("tc1", 0)) == 0:
            return [Msg("TIMESYNC", {"tc1": self.time_us * 1000, "ts1": int(msg.get("ts1", 0))})]
        return []

    def _on_obstacle_distance(self, msg: Msg) -> list[Msg]:
        """mavlink_receiver.cpp ``handle_message_obstacle_distance``: a companion's scan becomes
        ``obstacle_distance`` (stamped on arrival; ``increment_f`` when set, else ``increment``)."""
        f = msg.fields
        inc = float(f.get("increment_f", 0.0) or 0.0)
        inc = inc if inc > 0.0 else float(f.get("increment", 0))
        distances = tuple(int(d) for d in f.get("distances", ()))[:72]
        od = topics.ObstacleDistance(
            self.time_us, inc, float(f.get("angle_offset", 0.0)),
            distances + (65535,) * (72 - len(distances)), int(f.get("min_distance", 0)),
            int(f.get("max_distance", 0)), int(f.get("frame", 0)), int(f.get("sensor_type", 0)),
        )  # fmt: skip
        self.recorder.data(od)
        cp = self.ctrl.velocity_constraint
        if isinstance(cp, CollisionPrevention):
            cp.obstacle = od
        return []

    def _on_ftp(self, msg: Msg) -> list[Msg]:
        """MAVLink FTP: not modelled; a NAK UnknownCommand at once (``mavlink_ftp``), said once."""
        if msg.get("target_system", 1) not in (0, mav.SYSTEM_ID):
            return []
        if not self._ftp_said:
            self._ftp_said = True
            self.text(MavSeverity.WARNING, "MAVLink FTP not supported by the built-in simulator")
        fields = {"target_network": 0, "target_system": msg.sysid, "target_component": msg.compid}
        return [Msg("FILE_TRANSFER_PROTOCOL", {**fields, "payload": nak(msg.get("payload", ()))})]

    def _on_mission_set_current(self, msg: Msg) -> list[Msg]:
        self.nav.set_current(int(msg.get("seq", 0)), self.time_us / 1e6)
        self.drain_nav_events()
        return []

    _RECEIVE: ClassVar[dict[str, Callable[[Vehicle, Msg], list[Msg]]]] = {
        "HEARTBEAT": _on_heartbeat,
        "COMMAND_LONG": _on_command,
        "COMMAND_INT": _on_command,
        "MANUAL_CONTROL": _on_manual_control,
        "SET_MODE": _on_set_mode,
        "TIMESYNC": _on_timesync,
        "MISSION_SET_CURRENT": _on_mission_set_current,
        "FILE_TRANSFER_PROTOCOL": _on_ftp,
        "OBSTACLE_DISTANCE": _on_obstacle_distance,
        "SET_POSITION_TARGET_LOCAL_NED": lambda self, msg: self.offboard.local_ned(msg),
        "SET_POSITION_TARGET_GLOBAL_INT": lambda self, msg: self.offboard.global_int(msg),
        "SET_ATTITUDE_TARGET": lambda self, msg: self.offboard.attitude_target(msg),
    }

    # ------------------------------------------------------------------ estimate

    def estimated_tilt(self, roll: float, pitch: float) -> tuple[float, float]:
        """EKF2's (roll, pitch) of a true (roll, pitch): off by its tilt error (``ekf2``)."""
        e = self.est
        c, s = math.cos(self.body.yaw), math.sin(self.body.yaw)
        return roll + (-s * e.tx + c * e.ty), pitch - (c * e.tx + s * e.ty)

    def _estimate(self) -> None:
        b, e, st = self.body, self.est, self.st
        st.x, st.y, st.z = b.x + e.ex, b.y + e.ey, b.z + e.ez
        st.yaw = b.yaw + e.eh
        st.vx, st.vy = b.vx + e.evx, b.vy + e.evy
        st.landed = self.land.landed

    # ------------------------------------------------------------------ 50 Hz

    def _thrust(
        self, hte: HoverThrustEstimator, dt: float, cax: float, cay: float, caz: float
    ) -> tuple[float, float, float]:
        """SIH's motors under PositionControl's acceleration setpoint: PX4 turns it into thrust
        with its hover thrust (``hte.used``), SIH lifts with the true one (``HOVER_THRUST``); the
        hover thrust estimator then learns from the vertical acceleration it measures."""
        lift = hte.used / HOVER_THRUST * (GRAVITY - caz)
        b = self.body
        # the vertical acceleration it measures, up: none while the ground holds the body
        acc_up = 0.0 if b.on_ground else DRAG_VERTICAL * b.vz - b.az
        thrust_up = hte.used * (GRAVITY - caz) / GRAVITY
        valid = hte.update(dt, acc_up, thrust_up, b.vz, math.hypot(b.vx, b.vy), -b.z, self.land.landed)
        if valid and self.params["MPC_USE_HTE"] and hte.hover != hte.used:
            previous, hte.used = hte.used, hte.hover
            self.ctrl.update_hover_thrust(previous, hte.used)
        s = lift / GRAVITY
        return cax * s, cay * s, GRAVITY - lift

    def _control_tick(self, t: int) -> None:
        dt = CONTROL_DT
        # SIH's range finder reads below its minimum on the ground: EKF2 fuses it again only
        # once landed (its on-ground reading), the estimate meanwhile shifts (ekf2.py)
        if self.body.on_ground and not self.land.landed:
            self.est.range_lost()
        else:
            self.est.range_fused(-self.body.z, self.land.landed)
        self.est.update_tilt(dt, self.commander.armed, not self.body.on_ground)
        # and with EKF2's roll and pitch off by (tx, ty), the body leans that much the other way
        self.body.lean_x, self.body.lean_y = self.est.tx, self.est.ty
        self.est.update(dt, self.body.vx, self.body.vy, self.body.yaw)
        self.wind.update(dt)
        if self._tick % (CONTROL_EVERY * 10) == 0:
            self.world.refresh_near(self.body.x, self.body.y)
        nav, st = self.nav, self.st
        nav.sample_x, nav.sample_y = st.x, st.y  # the navigator samples a tick behind
        self._estimate()
        sim = self.sim
        faulty = sim.faulty
        if faulty and sim.gps.blocked:  # dead reckoning: the horizontal estimate drifts
            g = sim.gps
            g.dead_reckon(dt)
            self.st.x += g.drift_x
            self.st.y += g.drift_y
        commander = self.commander
        commander.update(t)
        goal = self._goal_for(t)
        self.goal = goal
        if self._tick % (CONTROL_EVERY * 10) == 0:  # 5 Hz: GEOFENCE_CHECK_INTERVAL_US
            result = self.nav.geofence_breach_check(self.st, t, self.commander.armed)
            if result is not None:
                self.recorder.data(result)
        b, e, st = self.body, self.est, self.st
        cp = self.ctrl.velocity_constraint
        if sim.range_sensor is not None or cp is not None:
            self._range_and_cp_inputs(t, cp)  # type: ignore[arg-type]
        # PX4's rate controller integrates while the land detector says neither landed nor maybe
        b.rate_integrating = not (self.land.landed or self.land.maybe_landed)
        if commander.armed and not commander.crashed:
            self.ctrl.dist_bottom = -b.z  # SIH's downward range finder sees the true height
            cax, cay, caz, cyr = self.ctrl.update(
                dt, goal, st.x, st.y, st.z, b.vx + e.evx, b.vy + e.evy, b.vz + e.evz, st.yaw
            )
            self.ctrl.acc_sp = (cax, cay, caz)  # logged as vehicle_local_position_setpoint
            hte = sim.hover_thrust
            if hte is not None:
                cax, cay, caz = self._thrust(hte, dt, cax, cay, caz)
            # the attitude controller tilts the *estimated* body: with EKF2's heading off by eh,
            # the real thrust leans eh the other way (PX4 SIH: 2-5 degrees on a leg)
            c, s = math.cos(e.eh), math.sin(e.eh)
            self._cmd = (c * cax + s * cay, c * cay - s * cax, caz, cyr)
            b.motors = True
        else:
            self._cmd = IDLE
            b.motors = False
            self.ctrl.reset(st.x, st.y, st.z, 0.0, 0.0, 0.0, st.yaw)
            if sim.hover_thrust is not None:
                sim.hover_thrust.reset()
        if cp is not None and cp.fused is not None:
            self._cp_outputs(t, cp)  # type: ignore[arg-type]
        if faulty and sim.failure_injector.esc_blocked:
            self._motor_out(t, dt)
        if self._tick % (CONTROL_EVERY * 10) == 0:  # 5 Hz: battery, failure detector
            self._monitor(t)
        self.drain_nav_events()
        self._stream(t, faulty)
        if commander.nav_state is _ORBIT and self._tick % _ORBIT_STATUS_EVERY == 0:
            self._out.append(orbit_execution_status(self, t))  # every link (NORMAL mode's 2 Hz)
        self._log(t)
        if commander.close_log:
            commander.close_log = False
            self.recorder.stop()

    def _stream(self, t: int, faulty: bool) -> None:
        """The telemetry due at ``t`` on each link, each message built once per tick. Before the
        fix no GLOBAL_POSITION_INT / HOME_POSITION; no GLOBAL_POSITION_INT either while a failed
        GPS has left the estimate without a global position."""
        held = (
            _NEEDS_FIX
            if not self.commander.ready
            else _NO_GLOBAL
            if faulty and not self._global_valid(t)
            else ()
        )
        schedules = self.schedules
        out = self._out
        if len(schedules) == 1:
            for name in schedules[0].due(t):
                if name not in held:
                    msg = STREAMS[name](self, t)
                    if msg is not None:  # a stream whose topic has no news sends nothing
                        out.append(msg)
            return
        built: dict[str, Msg | None] = {}
        for i, schedule in enumerate(schedules):
            if not self.streaming[i]:
                continue  # nothing is built for a quiet link
            for name in schedule.due(t):
                if name not in held:
                    if name in built:
                        msg = built[name]
                    else:
                        msg = built[name] = STREAMS[name](self, t)
                    if msg is not None:
                        out.append((i, msg))

    def _setup_collision_prevention(self) -> None:
        """The position-mode task of MPC_POS_MODE, and its CollisionPrevention when PX4 would run
        it, with its parameters."""
        p = self.params
        self.ctrl.direct_velocity = int(p["MPC_POS_MODE"]) == 0
        self.ctrl.stick_acceleration = int(p["MPC_POS_MODE"]) == 4
        self.ctrl.hold_max_xy = p["MPC_HOLD_MAX_XY"]
        if not cp_runs(p):
            self.ctrl.velocity_constraint = None
            return
        params = CpParams(
            p["CP_DIST"], p["CP_DELAY"], p["CP_GUIDE_ANG"], bool(int(p["CP_GO_NO_DATA"])),
            p["MPC_XY_P"], p["MPC_JERK_MAX"], p["MPC_ACC_HOR"],
        )  # fmt: skip
        old = self.ctrl.velocity_constraint
        if isinstance(old, CollisionPrevention):
            old.params = params
        else:
            self.ctrl.velocity_constraint = CollisionPrevention(params, self.time_us)

    def _range_and_cp_inputs(self, t: int, cp: CollisionPrevention | None) -> None:
        """The range sensor's scan when due (logged, handed to CP); CP's time and attitude."""
        b = self.body
        rs = self.sim.range_sensor
        if rs is not None:
            out = rs.update(t, self.world, b.x, b.y, b.z, b.yaw)
            if out is not None:
                od, ds = out
                rec = self.recorder
                rec.data(od)
                if t - rs.logged_us >= 1_000_000:  # the logger takes distance_sensor at 1 Hz
                    rs.logged_us = t
                    rec.data(ds)
                if cp is not None:
                    cp.obstacle, cp.distance = od, ds
        if cp is not None:
            cp.now_us = t
            cp.pitch = b.tilt()[1]
            cp.max_speed = self.limits.vel_manual

    def _cp_outputs(self, t: int, cp: CollisionPrevention) -> None:
        """What CP published this tick (logged; OBSTACLE_DISTANCE streams it) and its Hold request."""
        fused, cp.fused = cp.fused, None
        assert fused is not None
        cp.published = fused
        self.recorder.data(fused)
        if cp.constraints is not None:
            self.recorder.data(cp.constraints)
        if cp.want_hold:  # _publishVehicleCmdDoLoiter: VEHICLE_CMD_DO_SET_MODE AUTO LOITER
            cp.want_hold = False
            self.commander.set_mode(NavState.AUTO_LOITER, announce=False)

    def _motor_out(self, t: int, dt: float) -> None:
        """A blocked motor (failure injection): a quadrotor cannot hold its attitude; it tumbles and
        falls (no usable thrust) until it hits the ground, a crash."""
        fi = self.sim.failure_injector
        if not fi.motor_out or not self.commander.armed or self.commander.crashed:
            return
        b = self.body
        if not b.on_ground:
            fi.falling = True
            fi.tumble = min(fi.tumble + TUMBLE_RATE * dt, math.pi)
        elif fi.falling:
            fi.falling = False
            self.commander.ground_impact(t)
            return
        self._cmd = IDLE
        b.motors = False

    def _monitor(self, t: int) -> None:
        """battery_simulator and the failure detector, at 5 Hz."""
        c = self.commander
        sim = self.sim
        bat = sim.battery
        if bat.enabled:
            bat.update(t, c.armed, self.body)
            if self.recorder.active:  # logged at 5 Hz
                self.recorder.data(bat.status)
        fi, fd = sim.failure_injector, sim.failure_detector
        if sim.faulty and fd.update(t, c.armed, fi.tumble, fi.offline_mask, self.params):
            c.status_dirty = True
        c.monitor(t)

    def _goal_for(self, t: int) -> Goal:
        """The flight task's goal: idle, the manual task of a stick mode, or the navigator's."""
        c = self.commander
        if not c.armed or c.crashed:
            return Goal(GoalKind.IDLE)
        landed = self.land.landed
        if t - c.armed_at_us < self.params["COM_SPOOLUP_TIME"] * 1e6 and landed:
            self.ctrl.tko_ramp_s = 0.0
            return Goal(GoalKind.IDLE)
        ns = c.nav_state
        if ns == NavState.OFFBOARD:
            if landed and not self.offboard.want_takeoff(self.st.z):
                self.ctrl.tko_ramp_s = 0.0  # PX4's takeoff ramp restarts from the ground
                return Goal(GoalKind.IDLE)
            return self.offboard.goal
        if ns in _NOT_NAVIGATOR:
            if ns is _DESCEND:  # FlightTaskDescend: level, sinking at MPC_LAND_SPEED, no position
                return Goal(GoalKind.ALTITUDE, vel=(math.nan, math.nan, self.limits.land_speed))
            kind = _MANUAL_GOAL.get(ns, GoalKind.ATTITUDE)
            if landed and c.sticks[2] <= 0.5 + self.params["MPC_HOLD_DZ"] / 2 and kind != GoalKind.ATTITUDE:
                self.ctrl.tko_ramp_s = 0.0  # TakeoffHandling: ready for takeoff again
                return Goal(GoalKind.IDLE)
            return Goal(kind, sticks=c.sticks)
        goal = self.nav.update(self.st, t / 1e6)
        planner = self.sim.planner
        if planner is None or ns is _ORBIT:  # FlightTaskOrbit has no avoidance
            return goal
        b, e, st = self.body, self.est, self.st
        return planner.update(t / 1e6, CONTROL_DT, st.x, st.y, st.z, st.yaw, b.vx + e.evx, b.vy + e.evy, goal)

    def _params_changed(self) -> None:
        for name in self.param_proto.changed:
            self.recorder.param(name, self.params.type_of(name) == ParamType.INT32, self.params[name])
        self.param_proto.changed.clear()
        self.limits = Limits.of(self.params)
        self.ctrl.lim = self.limits
        if self.body.yaw_rate_gains is not None:
            self.body.yaw_rate_gains = YawRateGains.of(self.params)
        self._setup_collision_prevention()
        self.sim.battery.update_params()
        self.commander.params_updated()

    # ------------------------------------------------------------------ navigator events

    def drain_nav_events(self) -> None:
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
                self._out.append(STREAMS["MISSION_CURRENT"](self, t))
                changed = True
            elif ev.kind is EventKind.FINISHED:
                changed = True
                self.commander.mission_finished(t)
            elif ev.kind is EventKind.FAILURE:  # the commander's failsafe sees nav.failure
                changed = True
            elif ev.kind is EventKind.TEXT:
                severity, text = ev.value  # type: ignore[misc]
                self.text(severity, text)
            elif ev.kind is EventKind.RTL and self.commander.nav_state == NavState.AUTO_MISSION:
                self.recorder.data(
                    topics.command(t, int(mav.MavCmd.NAV_RETURN_TO_LAUNCH), (0.0,) * 7, (1, 1), (1, 1), False)
                )
                self.commander.set_mode(NavState.AUTO_RTL, announce=False)
            elif ev.kind is EventKind.HOLD and self.commander.nav_state == NavState.AUTO_TAKEOFF:
                self.commander.intend(NavState.AUTO_LOITER)
                self.commander.switch(NavState.AUTO_LOITER, t, hold_z=float(ev.value))  # type: ignore[arg-type]
        if changed:
            self._log_mission_result()

    def _log_mission_result(self) -> None:
        nav = self.nav
        total = len(nav.mission)
        self.recorder.data(
            topics.MissionResult(
                self.time_us, 0, 0, self.commander.home_count, nav.reached, min(nav.current, 65535), total,
                nav.mission_valid, False, nav.finished, nav.failure, 0, 0, 0, 0,
            )
        )  # fmt: skip

    def text(self, severity: int, text: str) -> None:
        """A STATUSTEXT for every link, and the same line in the log."""
        if len(text) <= 50:
            self._out.append(
                Msg("STATUSTEXT", {"severity": int(severity), "text": text, "id": 0, "chunk_seq": 0})
            )
        else:  # MAVLink 2 STATUSTEXT chunks: one id, chunk_seq 0.., a short (or empty) last chunk
            self._text_id = self._text_id % 65535 + 1
            for seq, i in enumerate(range(0, len(text) // 50 * 50 + 1, 50)):
                chunk = {
                    "severity": int(severity),
                    "text": text[i : i + 50],
                    "id": self._text_id,
                    "chunk_seq": seq,
                }
                self._out.append(Msg("STATUSTEXT", chunk))
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
        ref = (self.config.home.lat, self.config.home.lon, self.home_alt)
        rec.data(
            topics.local_position(
                t,
                (st.x, st.y, st.z),
                (b.vx + e.evx, b.vy + e.evy, b.vz + e.evz),
                (b.kax, b.kay, b.kaz),
                st.yaw,
                ref,
                0,
                True,
                e.hagl(-b.z),  # SIH's downward range finder: the true height while fused
                e.terrain_valid,
                b.vz + e.z_deriv_error,
            )
        )
        if tick % (CONTROL_EVERY * 2) == 0:  # 25 Hz
            roll, pitch = b.tilt()
            er, ep = self.estimated_tilt(roll, pitch)
            q = topics.quaternion(er, ep, st.yaw)
            rec.data(topics.VehicleAttitude(t, t, q, (0.0, 0.0, 0.0, 0.0), 0))
            # the truth next to the estimate, as PX4 SITL logs it (SIH's *_groundtruth topics)
            qt = topics.quaternion(roll, pitch, b.yaw)
            rec.data(topics.VehicleAttitudeGroundtruth(t, t, qt, (0.0, 0.0, 0.0, 0.0), 0))
            p, q_rate, r = b.rates()
            t0, p0, q0, r0 = self._logged_rates
            k = 1e6 / (t - t0) if t > t0 else 0.0
            rec.data(
                topics.VehicleAngularVelocity(
                    t, t, (p, q_rate, r), ((p - p0) * k, (q_rate - q0) * k, (r - r0) * k)
                )
            )
            self._logged_rates = (t, p, q_rate, r)
        if tick % (CONTROL_EVERY * 5) == 0:  # 10 Hz
            rec.data(
                topics.local_position(
                    t,
                    (b.x, b.y, b.z),
                    (b.vx, b.vy, b.vz),
                    (b.kax, b.kay, b.kaz),
                    b.yaw,
                    ref,
                    0,
                    True,
                    -b.z,
                    cls=topics.VehicleLocalPositionGroundtruth,
                )
            )
            lat, lon = self.proj.reproject(st.x, st.y)
            alt = self.home_alt - st.z
            if not self.sim.faulty or self._global_valid(t):  # EKF2 publishes none without one
                rec.data(
                    topics.VehicleGlobalPosition(
                        t, t, lat, lon, alt, alt, 0.3, 0.4, self.home_alt, True, False
                    )
                )
            c = self.ctrl
            rec.data(
                topics.TrajectorySetpoint(
                    t, (c.px, c.py, c.pz), (c.vx, c.vy, c.vz), (c.ax, c.ay, 0.0), c.yaw_sp, c.yawrate_sp
                )
            )
            if self.commander.armed:
                # PositionControl's output: the acceleration setpoint (NED, 0 in a hover) and
                # the thrust normalised by its hover thrust (the estimate's once valid, else
                # MPC_THR_HOVER), as PX4 converts one into the other
                ax, ay, az = c.acc_sp
                hte = self.sim.hover_thrust
                h = (hte.used if hte is not None else self.params["MPC_THR_HOVER"]) / GRAVITY
                if hte is not None:
                    rec.data(
                        topics.HoverThrustEstimate(
                            t, t, hte.hover, hte.variance, hte.innov, hte.innov_var, hte.ratio,
                            hte.accel_noise_var, hte.valid,
                        )
                    )  # fmt: skip
                rec.data(
                    topics.VehicleLocalPositionSetpoint(
                        t,
                        c.px,
                        c.py,
                        c.pz,
                        c.vsx,
                        c.vsy,
                        c.vsz,
                        (ax, ay, az),
                        # decoupled: tilted by the horizontal acceleration against g alone,
                        # then scaled so its vertical part is the vertical setpoint's
                        (
                            ax * h * (GRAVITY - az) / GRAVITY,
                            ay * h * (GRAVITY - az) / GRAVITY,
                            (az - GRAVITY) * h,
                        ),
                        c.yaw_sp,
                        c.yawrate_sp,
                    )
                )
            self._log_setpoint(t, self._triplet_goal())
        elif self.recorder.active and _triplet_key(self._triplet_goal()) != self._triplet_logged:
            # PX4's navigator publishes the triplet the cycle it changes, and the log carries that
            # publication's time: a waypoint's acceptance is not held back to the next 10 Hz sample
            self._log_setpoint(t, self._triplet_goal())
        commander = self.commander
        if commander.status_dirty or tick % (CONTROL_EVERY * 50) == 0:  # on change, else 1 Hz
            commander.status_dirty = False
            self._log_status(t)
        elif self.land.state() != self._land_logged:
            # PX4's land detector publishes whenever a stage changes (ground contact, maybe landed)
            self._log_land(t)

    def _log_status(self, t: int) -> None:
        c, rec = self.commander, self.recorder
        rec.data(c.status(t))
        self._log_land(t)
        rec.data(topics.ActuatorArmed(t, c.armed, False, c.ready, False, False, False))
        rec.data(self.sim.failure_detector.topic(t))

    def _log_land(self, t: int) -> None:
        self.recorder.data(self.land.topic(t, self.body, self.commander.crashed, self.goal.kind))
        self._land_logged = self.land.state()

    def _triplet_goal(self) -> Goal:
        """The goal position_setpoint_triplet shows: the navigator's, whatever avoidance flies."""
        planner = self.sim.planner
        return self.goal if planner is None or not planner.active else planner.goal

    def _log_setpoint(self, t: int, g: Goal) -> None:
        self._triplet_logged = _triplet_key(g)
        kind = _SETPOINT_TYPE.get(g.kind)
        if kind is None or not self.commander.armed:
            return
        lat, lon = self.proj.reproject(g.x, g.y)
        speed = g.speed if g.speed == g.speed else self.limits.cruise
        acc = g.acc_rad if g.acc_rad == g.acc_rad else self.params["NAV_ACC_RAD"]
        alt = g.alt_amsl if g.alt_amsl == g.alt_amsl else self.home_alt - g.z
        cur = topics.setpoint(t, lat, lon, alt, g.yaw, kind, acc, speed)
        # the track's start and the corner after the target, as PX4's navigator publishes them
        # (Mission::setActiveMissionItems); both logged as position setpoints
        prev = nxt = topics.INVALID_SETPOINT
        if g.kind is GoalKind.POSITION and g.prev[0] == g.prev[0]:
            plat, plon = self.proj.reproject(g.prev[0], g.prev[1])
            palt = self.home_alt - g.prev[2]
            prev = topics.setpoint(t, plat, plon, palt, math.nan, topics.SETPOINT_TYPE_POSITION, acc, speed)
        if g.kind is GoalKind.POSITION and g.next[0] == g.next[0]:
            nlat, nlon = self.proj.reproject(g.next[0], g.next[1])
            nalt = self.home_alt - g.next[2]
            nxt = topics.setpoint(t, nlat, nlon, nalt, math.nan, topics.SETPOINT_TYPE_POSITION, acc, speed)
        self.recorder.data(topics.PositionSetpointTriplet(t, prev, cur, nxt))
