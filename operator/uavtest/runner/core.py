"""The runner core: one replica's flight as a pure state machine (no sockets, no clocks).

Fed decoded messages (``uavtest.runner.events``) and the wall clock, it returns the messages to
send. Stages run in order — connect, params, mission, flight, settle, (log download), done — and
the core ends with a ``FlightReport``. The edge (``uavtest.runner.session``) moves the bytes.

Two clocks: protocol retries (params, mission, ACKs) run on the wall clock, because a lockstep
simulator answers while its clock stands still; commands, GCS heartbeats, the timeout and the
monitor run on the vehicle clock (time_boot_ms). In lockstep (the simulator announced
``LOCKSTEP``) the core grants vehicle time and does all its flight work between grants, so a run
is deterministic; setup (params, mission) happens with the clock held. Grants are up to
``step_ms`` long, shorter only where the runner must act on time (``uavtest.runner.grants``).
Without announces (real PX4) the vehicle runs on its own and the core follows its telemetry.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum

from uavtest.runner.commands import CommandScheduler, FaultRecord, Refusal, StepKind, disarm_command
from uavtest.runner.events import (
    Attitude,
    CommandAck,
    ExtendedSysState,
    GcsHeartbeat,
    GlobalPosition,
    Heartbeat,
    HomePosition,
    Incoming,
    LocalPosition,
    LockstepAnnounce,
    LockstepGrant,
    LogData,
    LogEntry,
    MissionAck,
    MissionItemInt,
    MissionItemReached,
    MissionRequest,
    Outgoing,
    ParamValue,
    StatusText,
    SysStatus,
    VehicleTime,
)
from uavtest.runner.grants import DEFAULT_STEP_MS, FINE_MS, grant_until
from uavtest.runner.home import check_home
from uavtest.runner.logdownload import LogDownloader
from uavtest.runner.mission import MissionUploader
from uavtest.runner.monitor import FlightMonitor
from uavtest.runner.obstacle_distance import ObstacleDistanceFeed
from uavtest.runner.params import ParamSetter
from uavtest.runner.progress import ProgressWatch
from uavtest.runner.px4 import AckResult, Autopilot, Cmd, LandedState, MavType, mode_name, result_name
from uavtest.runner.reboot import JITTER_MS, clock_went_back, reboot_reason
from uavtest.runner.streams import stream_requests
from uavtest.spec.models import Command, Fault, FlightMode, Geofence, Home, Obstacle, RangeSensor

__all__ = ["ARM_GRACE_MS", "CoreConfig", "Ending", "FlightReport", "ReplicaCore", "Stage"]

log = logging.getLogger(__name__)

ARM_GRACE_MS = 1500  # vehicle ms after arming before a disarmed vehicle counts as landed


class Stage(StrEnum):
    CONNECT = "connect"
    PARAMS = "params"
    MISSION = "mission"
    FLIGHT = "flight"
    SETTLE = "settle"  # the verdict is settled: disarming so the log closes
    LOG = "log"  # downloading the log over MAVLink
    DONE = "done"


#: stages in which a vehicle clock that jumps back means the vehicle rebooted (uavtest.runner.reboot):
#: what the runner set up, flew or is downloading belongs to the previous boot
_REBOOT_WATCHED = frozenset({Stage.PARAMS, Stage.MISSION, Stage.FLIGHT, Stage.LOG})


class Ending(StrEnum):
    """Why the flight stage ended."""

    LANDED = "landed"  # armed, flew, disarmed, no command left
    COLLISION = "collision"
    BLOCKED = "blocked"  # in mission, no progress toward the next waypoint (uavtest.runner.progress)
    TIMEOUT = "timeout"
    REFUSED = "refused"  # the vehicle refused to arm until the runner gave up: no flight
    ERROR = "error"  # a bench fault: see FlightReport.error


@dataclass(frozen=True, slots=True)
class CoreConfig:
    """Everything the core needs to know about the test, already in wire form."""

    endpoint: str = "udpin:127.0.0.1:14540"
    params: dict[str, float | int] = field(default_factory=dict)
    mission: Sequence[MissionItemInt] = ()
    commands: Sequence[Command] = ()
    faults: Sequence[Fault] = ()  # injected with MAV_CMD_INJECT_FAILURE (params must enable it)
    home: Home = field(default_factory=Home)  # places local goto / orbit points
    obstacles: Sequence[Obstacle] = ()
    geofence: Geofence | None = None
    timeout_s: float = 600.0  # vehicle seconds from the start of the flight stage
    connect_timeout_s: float = 30.0  # wall seconds until the first heartbeat
    position_timeout_s: float = 120.0  # wall seconds from the heartbeat until a position
    silence_s: float = 10.0  # wall seconds without any message before the vehicle counts as gone
    step_ms: int = DEFAULT_STEP_MS  # the largest lockstep grant (vehicle ms)
    heartbeat_ms: int = 1000  # GCS heartbeat period
    retry_s: float = 1.0  # protocol retry interval (wall)
    settle_s: float = 3.0  # wall seconds to wait for the disarm after the verdict is settled
    arm_settle_s: float = 0.0  # vehicle seconds ready-to-arm before arming (0: arm when due)
    download_log: bool = False  # stage 6 over MAVLink (PX4 without a shared log directory)
    simulator: str | None = None  # "builtin" / "px4" / None (unknown vehicle): wording of UNSUPPORTED
    #: a scanning range sensor the runner simulates for the vehicle, sending its OBSTACLE_DISTANCE
    #: (PX4 SITL, whose SIH has none: ``uavtest.runner.obstacle_distance``); None: the vehicle's own
    range_sensor: RangeSensor | None = None


@dataclass(slots=True)
class FlightReport:
    """What the core saw: the input to the verdict (with the log) and to the result."""

    ending: Ending | None = None
    error: str | None = None
    lockstep: bool = False
    vehicle: Heartbeat | None = None
    start_ms: int | None = None  # vehicle time the flight stage began
    end_ms: int | None = None  # vehicle time the flight stage ended
    armed_ever: bool = False
    airborne: bool = False
    min_distance: float = math.inf
    collision: LocalPosition | None = None
    geofence_violation: float = 0.0
    mission_total: int = 0
    mission_reached: set[int] = field(default_factory=set)
    notes: list[str] = field(default_factory=list)
    delays: list[str] = field(default_factory=list)  # the command schedule shifted (SCHEDULE_SHIFTED)
    warnings: list[str] = field(default_factory=list)  # other warnings for the result (home altitude)
    status_texts: list[str] = field(default_factory=list)
    status_log: list[tuple[int, int, str]] = field(default_factory=list)  # (vehicle ms, severity, text)
    refusals: list[Refusal] = field(default_factory=list)  # commands the vehicle refused
    faults: list[FaultRecord] = field(default_factory=list)  # faults injected, with their ACKs
    grants: int = 0
    #: the longest the runner fell behind the vehicle (vehicle ms between the oldest and the newest
    #: position of one batch of datagrams read at once), with a range sensor to feed
    scan_backlog_ms: int = 0
    log_data: bytes | None = None
    flight_wall: tuple[float, float] | None = None  # wall clock at the flight stage's start and end

    @property
    def sim_time(self) -> float | None:
        if self.start_ms is None or self.end_ms is None:
            return None
        return (self.end_ms - self.start_ms) / 1000.0


SCAN_STALE_MS = 500  # PX4's CollisionPrevention RANGE_STREAM_TIMEOUT_US


class ReplicaCore:
    """The stage machine. Call ``start``, then ``handle`` per message and ``tick`` now and then."""

    def __init__(self, config: CoreConfig) -> None:
        self.cfg = config
        self.stage = Stage.CONNECT
        self.report = FlightReport(mission_total=len(config.mission))
        self.now_ms = 0  # vehicle clock: the latest time_boot_ms seen
        self.armed = False
        self.landed_state = int(LandedState.UNDEFINED)
        self.monitor = FlightMonitor(config.obstacles, config.geofence)
        self.progress = ProgressWatch(config.mission, config.home)
        self._in_mission = False  # the vehicle's latest heartbeat says mission mode
        self.params = ParamSetter(config.params, retry_s=config.retry_s)
        self.uploader = MissionUploader(config.mission, retry_s=config.retry_s)
        self.scheduler = CommandScheduler(
            config.commands,
            faults=config.faults,
            home=config.home,
            ack_timeout_s=config.retry_s,
            arm_settle_ms=round(config.arm_settle_s * 1000),
            simulator=config.simulator,
        )
        self.downloader = LogDownloader(retry_s=config.retry_s)
        self.obstacle_feed = (
            ObstacleDistanceFeed(config.range_sensor, config.obstacles) if config.range_sensor else None
        )
        self._scan_from: LocalPosition | None = None  # the batch's newest position, to scan from
        self._batch_first_ms: int | None = None  # the batch's oldest position (vehicle ms)
        self._have_local = False
        self._have_global = False
        self._waiting_at: int | None = None  # a lockstep announce not yet granted
        self._last_grant: LockstepGrant | None = None
        self._last_rx = 0.0
        self._deadline = math.inf  # connect / position / settle deadline (wall)
        self._next_wall_heartbeat = 0.0
        self._last_hb_ms = -math.inf
        self._settle_tries = 0
        self._armed_at_ms = -math.inf  # vehicle time the vehicle was last seen arming
        self._disarmed_at_ms = -1  # vehicle time when it was last seen disarming
        self._last_announce_ms = -1  # the latest lockstep announce (the simulator's exact clock)
        self._home_checked = False  # a HOME_POSITION has been compared with the test's home
        self._home_warned = False

    # ------------------------------------------------------------------ public

    @property
    def done(self) -> bool:
        return self.stage is Stage.DONE

    @property
    def lockstep(self) -> bool:
        return self.report.lockstep

    def start(self, wall: float) -> list[Outgoing]:
        """Begin: wait for the vehicle (a udpin link has nobody to talk to until it speaks)."""
        self._last_rx = wall
        self._deadline = wall + self.cfg.connect_timeout_s
        return []

    def handle(self, msg: Incoming, wall: float) -> list[Outgoing]:
        """One decoded message from the vehicle."""
        self._last_rx = wall
        # the hot messages first: positions and lockstep announces arrive every step
        if isinstance(msg, LocalPosition):
            return self._on_position(msg, wall)
        if isinstance(msg, LockstepAnnounce):
            return self._on_announce(msg, wall)
        if isinstance(msg, Heartbeat):
            return self._on_heartbeat(msg, wall)
        if isinstance(msg, Attitude):
            if self.obstacle_feed is not None:
                self.obstacle_feed.on_attitude(msg.yaw)
            return []
        if isinstance(msg, GlobalPosition | VehicleTime):
            if msg.time_ms > self.now_ms:
                self.now_ms = msg.time_ms
            elif msg.time_ms < self.now_ms - JITTER_MS and self.stage in _REBOOT_WATCHED:
                return self._rebooted(msg.time_ms, wall)
            if isinstance(msg, GlobalPosition) and not self._have_global:
                self._have_global = True
                return self._advance(wall)
            return []
        if isinstance(msg, CommandAck):
            return self._on_command_ack(msg, wall)
        if isinstance(msg, HomePosition):
            return self._on_home(msg, wall)
        if isinstance(msg, ExtendedSysState):
            self.landed_state = msg.landed_state
            return []
        if isinstance(msg, SysStatus):
            self.scheduler.on_sys_status(msg.ready_to_arm, self.now_ms)
            return []
        if isinstance(msg, MissionItemReached):
            self.report.mission_reached.add(msg.seq)
            self.progress.on_reached(msg.seq)
            return []
        if isinstance(msg, StatusText):
            text = f"t={self.now_ms / 1000:.2f} s: {msg.text}"
            self.report.status_texts.append(text)
            self.report.status_log.append((self.now_ms, msg.severity, msg.text))
            log.info("vehicle says: %s", text)
            return []
        if isinstance(msg, ParamValue) and self.stage is Stage.PARAMS:
            return self.params.handle(msg, wall) + self._advance(wall)
        if isinstance(msg, MissionRequest | MissionAck) and self.stage is Stage.MISSION:
            return self.uploader.handle(msg, wall) + self._advance(wall)
        if isinstance(msg, LogEntry | LogData) and self.stage is Stage.LOG:
            return self.downloader.handle(msg, wall) + self._advance(wall)
        return []  # MissionCurrent, and answers that belong to no running stage

    def tick(self, wall: float) -> list[Outgoing]:
        """Time passed on the wall clock: retries, deadlines, and (without lockstep) the flight."""
        stage = self.stage
        if stage is Stage.DONE:
            return []
        if stage is not Stage.CONNECT and wall - self._last_rx > self.cfg.silence_s:
            silent = f"no MAVLink message for {self.cfg.silence_s:g} s (simulator died?)"
            return self._fail(f"vehicle on {self.cfg.endpoint} went silent: {silent}")
        out: list[Outgoing] = []
        setup = stage in (Stage.CONNECT, Stage.PARAMS, Stage.MISSION, Stage.LOG)
        if setup and self.report.vehicle and wall >= self._next_wall_heartbeat:
            self._next_wall_heartbeat = wall + self.cfg.heartbeat_ms / 1000.0
            out.append(GcsHeartbeat())
        if stage is Stage.CONNECT:
            if wall >= self._deadline:
                if self.report.vehicle is None:
                    return self._fail(
                        f"no heartbeat from {self.cfg.endpoint} within {self.cfg.connect_timeout_s:g} s"
                    )
                waited = f"{self.cfg.position_timeout_s:g} s"
                return self._fail(f"vehicle on {self.cfg.endpoint} sent no position within {waited}")
            if self.lockstep and self._last_grant and wall - self._last_rx > self.cfg.retry_s:
                out.append(self._last_grant)  # the grant or the announce got lost
        elif stage is Stage.PARAMS:
            out += self.params.tick(wall)
        elif stage is Stage.MISSION:
            out += self.uploader.tick(wall)
        elif stage is Stage.FLIGHT:
            if self.lockstep:
                if self._last_grant and wall - self._last_rx > self.cfg.retry_s:
                    out.append(self._last_grant)
            else:
                out += self._flight_step(wall)
        elif stage is Stage.SETTLE:
            out += self._settle_tick(wall)
        elif stage is Stage.LOG:
            out += self.downloader.tick(wall)
        return out + self._advance(wall)

    # ------------------------------------------------------------------ messages

    def _on_position(self, p: LocalPosition, wall: float) -> list[Outgoing]:
        if p.time_ms > self.now_ms:
            self.now_ms = p.time_ms
        elif p.time_ms < self.now_ms - JITTER_MS and self.stage in _REBOOT_WATCHED:
            return self._rebooted(p.time_ms, wall)
        if self.obstacle_feed is not None and self.stage is not Stage.DONE:
            self._scan_from = p  # scanned once the batch is read (``end_batch``)
            if self._batch_first_ms is None:
                self._batch_first_ms = p.time_ms
        return self._position_step(p, wall)

    def end_batch(self, wall: float) -> list[Outgoing]:
        """After the messages of one read: the range sensor's scan, from the newest position.

        A runner that fell behind (PX4 at a high speed factor on a busy machine) reads many
        positions at once; scanning from each in turn would hand PX4's Collision Prevention
        scans from where the vehicle was, stamped by PX4 as new. One scan from the newest
        position keeps them as fresh as the runner can; how far behind it fell is reported."""
        p = self._scan_from
        if p is None:  # no range sensor to feed, or no position in this read
            return []
        first, self._scan_from, self._batch_first_ms = self._batch_first_ms, None, None
        if self.obstacle_feed is None or self.stage is Stage.DONE:
            return []
        # before the flight a read holds what queued while connecting: not a backlog
        backlog = p.time_ms - first if first is not None and self.stage is Stage.FLIGHT else 0
        if backlog > self.report.scan_backlog_ms:
            if backlog > SCAN_STALE_MS:
                log.info(
                    "t=%.2f s: the runner read %.1f s of vehicle time at once (its scans lag that much)",
                    p.time_ms / 1000,
                    backlog / 1000,
                )
            self.report.scan_backlog_ms = backlog
        scan = self.obstacle_feed.on_position(p.time_ms, p.x, p.y, p.z)
        return [scan] if scan is not None else []

    def _position_step(self, p: LocalPosition, wall: float) -> list[Outgoing]:
        """A position's work for the stage: the flight's checks and step, or the connection."""
        if self.stage is Stage.FLIGHT:
            self.monitor.on_position(p)
            flying = self._in_mission and self.armed and self.monitor.airborne
            self.progress.on_position(p.x, p.y, p.z, p.time_ms, flying)
            if not self.lockstep:
                return self._flight_step(wall)
            return []
        if not self._have_local:
            self._have_local = True
            return self._advance(wall)
        return []

    def _on_heartbeat(self, hb: Heartbeat, wall: float) -> list[Outgoing]:
        if hb.autopilot == Autopilot.INVALID or hb.type in (MavType.GCS, MavType.ONBOARD_CONTROLLER):
            return []  # another ground station or companion, not the vehicle
        first = self.report.vehicle is None
        before = self.report.vehicle
        if before is None or hb.custom_mode != before.custom_mode or hb.armed != self.armed:
            state = "armed" if hb.armed else "disarmed"
            log.info("vehicle %d/%d: %s, %s", hb.sysid, hb.compid, mode_name(hb.custom_mode), state)
        self.report.vehicle = hb
        self._in_mission = mode_name(hb.custom_mode) == FlightMode.MISSION.value
        if hb.armed and not self.armed:
            self._armed_at_ms = self.now_ms
        elif self.armed and not hb.armed:
            self._disarmed_at_ms = self.now_ms
        self.armed = hb.armed
        if hb.armed and self.stage is Stage.FLIGHT:
            self.report.armed_ever = True
        if first:
            self._deadline = wall + self.cfg.position_timeout_s
            return [GcsHeartbeat(), *self._advance(wall)]
        return self._advance(wall)

    def _on_home(self, home: HomePosition, wall: float) -> list[Outgoing]:
        """The start-up home against the test's: every HOME_POSITION until the vehicle arms, and
        the first one in any case (the home moves only with the vehicle once it has armed)."""
        if self._home_checked and self.report.armed_ever:
            return []
        first = not self._home_checked
        self._home_checked = True
        check = check_home(self.cfg.home, home)
        if first:
            log.info("vehicle home %.1f m from world.home, %+.1f m up", check.horizontal_m, check.vertical_m)
        if check.warning and not self._home_warned:
            self._home_warned = True
            log.warning("%s", check.warning)
            self.report.warnings.append(check.warning)
        if check.error is None:
            return []
        if self.stage is Stage.FLIGHT:
            return self._settle(Ending.ERROR, wall, error=check.error)
        if self.stage in (Stage.CONNECT, Stage.PARAMS, Stage.MISSION):
            return self._fail(check.error)
        return []

    def _on_announce(self, a: LockstepAnnounce, wall: float) -> list[Outgoing]:
        if not self.report.lockstep:
            log.info("vehicle runs in lockstep: granting up to %d ms at a time", self.cfg.step_ms)
            self.report.lockstep = True
        if clock_went_back(self._last_announce_ms, a.time_ms, jitter_ms=0) and self.stage in _REBOOT_WATCHED:
            return self._rebooted(a.time_ms, wall)
        self._last_announce_ms = a.time_ms
        if a.time_ms > self.now_ms:
            self.now_ms = a.time_ms
        self._waiting_at = a.time_ms
        out = self._advance(wall)
        if self.stage is Stage.CONNECT:
            out.append(self._grant())  # the vehicle needs time to produce a position
        elif self.stage is Stage.FLIGHT:
            out += self._flight_step(wall)
            if self.stage is Stage.FLIGHT:
                out.append(self._grant())
        return out

    def _on_command_ack(self, ack: CommandAck, wall: float) -> list[Outgoing]:
        if self.stage is Stage.FLIGHT:
            accepted = self.scheduler.handle_ack(ack, self.now_ms, wall)
            if accepted is not None and accepted.kind in (StepKind.ARM, StepKind.DISARM):
                # the heartbeat (1 Hz) will confirm it; until then trust the ACK
                self.armed = accepted.kind is StepKind.ARM
                if self.armed:
                    self.report.armed_ever = True
                    self._armed_at_ms = self.now_ms
                else:
                    self._disarmed_at_ms = self.now_ms
            if not self.lockstep:
                return self._flight_step(wall)
            return []
        if self.stage is Stage.SETTLE and ack.command == Cmd.COMPONENT_ARM_DISARM:
            if ack.result == AckResult.ACCEPTED:
                self.armed = False
            else:  # e.g. already disarmed after a crash: nothing more to do
                self.report.notes.append(f"force disarm answered {result_name(AckResult, ack.result)}")
            return self._end_settle(wall)
        return []

    # ------------------------------------------------------------------ stages

    def _grant(self) -> LockstepGrant:
        seen = self._waiting_at if self._waiting_at is not None else self.now_ms
        if self.stage is Stage.FLIGHT:
            sched, start = self.scheduler, self.report.start_ms
            timeout_at = math.inf if start is None else start + self._timeout_ms(seen)
            until = grant_until(
                seen,
                max_ms=self.cfg.step_ms,
                busy=sched.busy,
                sticks=sched.sticks is not None,
                obstacle_distance=self.monitor.last_distance,
                next_event_ms=min(sched.next_event_ms, timeout_at, self._last_hb_ms + self.cfg.heartbeat_ms),
            )
        else:  # connecting (until the first position) and the last step after the disarm
            until = grant_until(seen, max_ms=min(self.cfg.step_ms, FINE_MS))
        grant = LockstepGrant(seen, until)
        self._waiting_at = None
        self._last_grant = grant
        self.report.grants += 1
        return grant

    def _advance(self, wall: float) -> list[Outgoing]:
        """Move through the stages whose work is finished."""
        out: list[Outgoing] = []
        while True:
            stage = self.stage
            if stage is Stage.CONNECT:
                if not (self.report.vehicle and self._have_local and self._have_global):
                    return out
                log.info("connected at vehicle time %.2f s", self.now_ms / 1000)
                self.stage = Stage.PARAMS
                out += stream_requests(attitude=self.obstacle_feed is not None)
                out += self.params.start(wall)
            elif stage is Stage.PARAMS:
                if not self.params.done:
                    return out
                if self.params.error:
                    return out + self._fail(self.params.error)
                self.stage = Stage.MISSION
                if self.cfg.mission:
                    out += self.uploader.start(wall)
                else:
                    self.uploader.done = True
            elif stage is Stage.MISSION:
                if not self.uploader.done:
                    return out
                if self.uploader.error:
                    return out + self._fail(self.uploader.error)
                if self.cfg.mission:
                    self.scheduler.mission_accepted_ms = self.now_ms
                self.stage = Stage.FLIGHT
                self.report.start_ms = self.now_ms
                self.report.armed_ever = self.armed
                self.report.flight_wall = (wall, wall)
                log.info("flight starts at vehicle time %.2f s", self.now_ms / 1000)
                if self.lockstep and self._waiting_at is not None:
                    out += self._flight_step(wall)
                    if self.stage is Stage.FLIGHT:
                        out.append(self._grant())
                elif not self.lockstep:
                    out += self._flight_step(wall)
                return out
            elif stage is Stage.LOG:
                if not self.downloader.done:
                    return out
                if self.downloader.error:
                    self.report.error = self.downloader.error
                self.report.log_data = self.downloader.data
                self.stage = Stage.DONE
                return out
            else:
                return out

    def _flight_step(self, wall: float) -> list[Outgoing]:
        """The flight's work at the current vehicle time: commands, heartbeat, checks."""
        now = self.now_ms
        out = self.scheduler.update(now, wall, armed=self.armed)
        if now - self._last_hb_ms >= self.cfg.heartbeat_ms:
            self._last_hb_ms = now
            out.append(GcsHeartbeat())
        rep = self.report
        if self.armed:
            rep.armed_ever = True
        if self.scheduler.error:
            return out + self._settle(Ending.ERROR, wall, error=self.scheduler.error)
        if self.scheduler.gave_up is not None and not self.armed:
            return out + self._settle(Ending.REFUSED, wall)
        mon = self.monitor
        if mon.collision is not None:
            c = mon.collision
            rep.notes.append(
                f"collision at t={c.time_ms / 1000:.2f} s, NED ({c.x:.2f}, {c.y:.2f}, {c.z:.2f})"
            )
            return out + self._settle(Ending.COLLISION, wall)
        if self.progress.blocked is not None and self.armed:
            rep.notes.append(self.progress.blocked)
            return out + self._settle(Ending.BLOCKED, wall)
        # landed: disarmed after arming, nothing left to do (a heartbeat from before the arming,
        # arriving after its ACK, must not end the flight: hence the grace after arming). Without
        # lockstep, only once the vehicle clock moved on after the disarm: a rebooted vehicle is
        # disarmed too, and its clock starts over (uavtest.runner.reboot)
        if (
            rep.armed_ever
            and not self.armed
            and self.scheduler.idle
            and now - self._armed_at_ms >= ARM_GRACE_MS
            and (self.lockstep or now > self._disarmed_at_ms)
        ):
            return out + self._settle(Ending.LANDED, wall)
        assert rep.start_ms is not None
        if now - rep.start_ms >= self._timeout_ms(now):
            if not rep.armed_ever and self.scheduler.refusals:
                rep.notes.append(f"timeout after {self.cfg.timeout_s:g} s of vehicle time, never armed")
                return out + self._settle(Ending.REFUSED, wall)  # the vehicle's doing, not the bench's
            if not rep.armed_ever:
                why = f"timeout: the vehicle never armed in {self.cfg.timeout_s:g} s of vehicle time"
                return out + self._settle(Ending.ERROR, wall, error=why)
            waited = self.scheduler.settle_waited_ms(now) / 1000
            extra = f" (and {waited:.1f} s waiting for the vehicle to settle before arming)" if waited else ""
            rep.notes.append(f"timeout after {self.cfg.timeout_s:g} s of vehicle time{extra}")
            return out + self._settle(Ending.TIMEOUT, wall)
        return out

    def _timeout_ms(self, now_ms: float) -> float:
        """The test's timeout from the flight's start, in vehicle ms, plus the time the runner
        held the arm for the vehicle to settle (``arm_settle``): PX4 needs that wait, the built-in
        vehicle does not, and a test's timeout means the same flight on both."""
        return self.cfg.timeout_s * 1000.0 + self.scheduler.settle_waited_ms(now_ms)

    def _settle(self, ending: Ending, wall: float, *, error: str | None = None) -> list[Outgoing]:
        rep = self.report
        rep.ending = ending
        rep.error = error or rep.error
        if rep.flight_wall is not None:
            rep.flight_wall = (rep.flight_wall[0], wall)
        self._snapshot()
        log.info(
            "flight ends at vehicle time %.2f s: %s%s",
            self.now_ms / 1000,
            ending,
            f" ({error})" if error else "",
        )
        self.stage = Stage.SETTLE
        self._settle_tries = 0
        if not self.armed and ending is Ending.LANDED:
            return self._end_settle(wall)
        return self._send_disarm(wall)

    def _snapshot(self) -> None:
        rep, mon = self.report, self.monitor
        rep.end_ms = self.now_ms
        rep.airborne = mon.airborne
        rep.min_distance = mon.min_distance
        rep.collision = mon.collision
        rep.geofence_violation = mon.geofence_violation
        rep.notes.extend(self.scheduler.notes)
        rep.delays = list(self.scheduler.warnings)
        rep.refusals = list(self.scheduler.refusals)
        rep.faults = list(self.scheduler.faults)
        if rep.scan_backlog_ms > SCAN_STALE_MS:  # once: a flight is snapshot when it ends
            rep.warnings.append(
                f"the runner fell up to {rep.scan_backlog_ms / 1000:.1f} s of vehicle time "
                "behind the vehicle (that much of its messages read at once): its range sensor's scans "
                f"were that old, and PX4 drops OBSTACLE_DISTANCE older than {SCAN_STALE_MS / 1000:g} s "
                "(Collision Prevention then holds the vehicle); a lower vehicle.speedFactor keeps up"
            )

    def _send_disarm(self, wall: float) -> list[Outgoing]:
        self._settle_tries += 1
        self._deadline = wall + self.cfg.retry_s
        return [disarm_command(force=True)]

    def _settle_tick(self, wall: float) -> list[Outgoing]:
        if not self.armed and self._settle_tries:
            return self._end_settle(wall)
        if wall < self._deadline:
            return []
        if self._settle_tries >= self.cfg.settle_s / self.cfg.retry_s:
            self.report.notes.append("the vehicle did not confirm the disarm")
            return self._end_settle(wall)
        return self._send_disarm(wall)

    def _end_settle(self, wall: float) -> list[Outgoing]:
        out: list[Outgoing] = []
        if self.lockstep and self._waiting_at is not None:
            out.append(self._grant())  # one more step, so the simulator acts on the disarm and closes its log
        rep = self.report
        never_armed_refusal = rep.ending is Ending.REFUSED and not rep.armed_ever  # no log to fetch
        if self.cfg.download_log and rep.ending is not Ending.ERROR and not never_armed_refusal:
            self.stage = Stage.LOG
            out += self.downloader.start(wall)
        else:
            self.stage = Stage.DONE
        return out

    def _rebooted(self, seen_ms: int, wall: float) -> list[Outgoing]:
        """The vehicle's clock went back: a new boot (the simulator restarted). A bench error."""
        reason = reboot_reason(self.stage.value, self.now_ms, seen_ms)
        self._waiting_at = None  # the new boot's announce is not ours to grant
        if self.stage is Stage.FLIGHT:
            self.armed = False  # a new boot is disarmed
            return self._settle(Ending.ERROR, wall, error=reason)
        return self._fail(reason)

    def _fail(self, reason: str) -> list[Outgoing]:
        """A bench fault before or outside the flight: stop here."""
        rep = self.report
        rep.ending = Ending.ERROR
        rep.error = reason
        if rep.start_ms is not None and rep.end_ms is None:
            self._snapshot()
        log.error("%s", reason)
        self.stage = Stage.DONE
        return []
