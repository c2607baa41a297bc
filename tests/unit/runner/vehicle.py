"""A scripted MAVLink vehicle for the core's unit tests: answers the protocols, flies nothing.

Tests push telemetry themselves; this only answers what the core sends (params, mission,
commands) and remembers the grants, so a test reads like the message sequence on the wire.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from uavtest.runner.core import ReplicaCore
from uavtest.runner.events import (
    CommandAck,
    CommandLong,
    GlobalPosition,
    Heartbeat,
    Incoming,
    LocalPosition,
    LockstepGrant,
    MissionAck,
    MissionCount,
    MissionItemInt,
    MissionRequest,
    Outgoing,
    ParamRequestRead,
    ParamSet,
    ParamValue,
)
from uavtest.runner.px4 import AckResult, Cmd, ParamType


def heartbeat(*, armed: bool = False, custom_mode: int = 0) -> Heartbeat:
    return Heartbeat(1, 1, 2, 12, 128 | 1 if armed else 1, custom_mode, 4)


@dataclass
class ScriptedVehicle:
    param_types: dict[str, int] = field(default_factory=dict)
    params: dict[str, float] = field(default_factory=dict)
    mission: list[MissionItemInt] = field(default_factory=list)
    armed: bool = False
    refuse_arm: bool = False
    beat_on_ack: bool = True  # a heartbeat right after each COMMAND_ACK (real vehicles: 1 Hz)
    grants: list[LockstepGrant] = field(default_factory=list)
    commands: list[CommandLong] = field(default_factory=list)  # the flight's commands
    intervals: dict[int, float] = field(default_factory=dict)  # SET_MESSAGE_INTERVAL: msg id → µs
    sent: list[Outgoing] = field(default_factory=list)
    _count: int = 0

    def answer(self, out: list[Outgoing]) -> list[Incoming]:
        replies: list[Incoming] = []
        for msg in out:
            self.sent.append(msg)
            if isinstance(msg, ParamRequestRead):
                ptype = self.param_types.get(msg.name, int(ParamType.REAL32))
                replies.append(ParamValue(msg.name, self.params.get(msg.name, 0.0), ptype))
            elif isinstance(msg, ParamSet):
                self.params[msg.name] = msg.value
                replies.append(ParamValue(msg.name, msg.value, msg.param_type))
            elif isinstance(msg, MissionCount):
                self._count = msg.count
                self.mission = []
                replies.append(MissionRequest(0))
            elif isinstance(msg, MissionItemInt):
                self.mission.append(msg)
                if msg.seq + 1 < self._count:
                    replies.append(MissionRequest(msg.seq + 1))
                else:
                    replies.append(MissionAck(0))
            elif isinstance(msg, CommandLong) and msg.command == Cmd.SET_MESSAGE_INTERVAL:
                self.intervals[int(msg.params[0])] = msg.params[1]
                replies.append(CommandAck(msg.command, AckResult.ACCEPTED))
            elif isinstance(msg, CommandLong):
                self.commands.append(msg)
                result = AckResult.ACCEPTED
                if msg.command == Cmd.COMPONENT_ARM_DISARM:
                    if msg.params[0] == 1.0 and self.refuse_arm:
                        result = AckResult.DENIED
                    else:
                        self.armed = msg.params[0] == 1.0
                replies.append(CommandAck(msg.command, result))
                if self.beat_on_ack:
                    replies.append(heartbeat(armed=self.armed))
            elif isinstance(msg, LockstepGrant):
                self.grants.append(msg)
        return replies


def exchange(core: ReplicaCore, vehicle: ScriptedVehicle, messages: list[Incoming], wall: float) -> None:
    """Feed messages to the core and the vehicle's answers back, until both are quiet."""
    queue = list(messages)
    while queue:
        msg = queue.pop(0)
        queue.extend(vehicle.answer(core.handle(msg, wall)))


def boot(time_ms: int = 0) -> list[Incoming]:
    """What a vehicle sends first: heartbeat, local and global position."""
    return [
        heartbeat(),
        LocalPosition(time_ms, 0.0, 0.0, 0.0),
        GlobalPosition(time_ms, 473977420, 85455940, 0),
    ]
