"""Offboard setpoints, goto / orbit / land_start / yaw and injected faults: the MAVLink each becomes
(checked against pymavlink's message definitions) and the scheduler's streaming, ordering and ACK
rules over a scripted vehicle."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from uavtest import mavlink_numbers as mav
from uavtest.analysis.verdict import flight_intent
from uavtest.runner.commands import (
    OFFBOARD_WARMUP_MS,
    CommandScheduler,
    expand,
    fault_command,
    goto_command,
    land_start_command,
    mode_command,
    orbit_command,
    position_target,
    yaw_command,
)
from uavtest.runner.core import ReplicaCore
from uavtest.runner.events import (
    CommandAck,
    CommandInt,
    CommandLong,
    LockstepAnnounce,
    PositionTargetGlobal,
    PositionTargetLocal,
)
from uavtest.runner.link import MavlinkCodec
from uavtest.runner.plan import flight_params, plan_flight
from uavtest.runner.px4 import AckResult, Cmd
from uavtest.spec.geo import ned_to_geodetic
from uavtest.spec.models import (
    Command,
    Fault,
    FlightMode,
    Goto,
    Home,
    Orbit,
    Setpoint,
    UavTestSpec,
    YawCommand,
)

from .vehicle import ScriptedVehicle, boot, exchange

HOME = Home(lat=47.397742, lon=8.545594, alt=488.0)
VEHICLE = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)


def cmd(at: float, action: str, **kw: object) -> Command:
    return Command.model_validate({"at": at, "action": action, **kw})


def wire(msg: object) -> mavlink2.MAVLink_message:
    """What pymavlink reads from the bytes the runner sends."""
    codec = MavlinkCodec(sysid=255, compid=190)
    codec.decode(bytes(VEHICLE.heartbeat_encode(2, 12, 0, 0, 3).pack(VEHICLE)))
    return mavlink2.MAVLink(None).decode(bytearray(codec.encode(msg)))  # type: ignore[arg-type]


# --------------------------------------------------------------------------- numbers


def test_new_mavlink_numbers_match_pymavlink() -> None:
    for name in ("DO_ORBIT", "CONDITION_YAW", "DO_LAND_START", "DO_REPOSITION", "INJECT_FAILURE"):
        assert getattr(mavlink2, f"MAV_CMD_{name}") == mav.MavCmd[name]
    for frame in mav.MavFrame:
        assert getattr(mavlink2, f"MAV_FRAME_{frame.name}") == frame
    for bit in mav.PositionTargetMask:
        assert getattr(mavlink2, f"POSITION_TARGET_TYPEMASK_{bit.name}") == bit
    for unit in mav.FailureUnit:
        assert getattr(mavlink2, f"FAILURE_UNIT_{unit.name}") == unit
    for kind in mav.FailureType:
        assert getattr(mavlink2, f"FAILURE_TYPE_{kind.name}") == kind
    assert mavlink2.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE == mav.REPOSITION_FLAGS_CHANGE_MODE


# --------------------------------------------------------------------------- encoding


M = mavlink2


def test_a_local_position_setpoint_with_yaw_is_mavsdks_position_mask() -> None:
    target = position_target(Setpoint(x=10, y=-5, z=-5, yaw=90))
    assert isinstance(target, PositionTargetLocal)
    ignored = (
        M.POSITION_TARGET_TYPEMASK_VX_IGNORE | M.POSITION_TARGET_TYPEMASK_VY_IGNORE
        | M.POSITION_TARGET_TYPEMASK_VZ_IGNORE | M.POSITION_TARGET_TYPEMASK_AX_IGNORE
        | M.POSITION_TARGET_TYPEMASK_AY_IGNORE | M.POSITION_TARGET_TYPEMASK_AZ_IGNORE
        | M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
    )  # fmt: skip
    assert target.type_mask == ignored == 0x09F8  # MAVSDK Offboard::set_position_ned
    m = wire(PositionTargetLocal(12_345, target.type_mask, 10, -5, -5, 0, 0, 0, math.radians(90), 0))
    assert m.get_type() == "SET_POSITION_TARGET_LOCAL_NED"
    assert (m.time_boot_ms, m.coordinate_frame, m.type_mask) == (12_345, M.MAV_FRAME_LOCAL_NED, 0x09F8)
    assert (m.x, m.y, m.z, m.target_system) == (10.0, -5.0, -5.0, 1)
    assert m.yaw == pytest.approx(math.pi / 2)


def test_a_velocity_setpoint_with_yaw_rate_ignores_position_and_yaw() -> None:
    target = position_target(Setpoint(vx=1, vy=-2, vz=-0.5, yaw_rate=-30))
    ignored = 7 | 448 | M.POSITION_TARGET_TYPEMASK_YAW_IGNORE
    assert target.type_mask == ignored
    assert (target.vx, target.vy, target.vz) == (1.0, -2.0, -0.5)
    assert target.yaw_rate == pytest.approx(math.radians(-30))
    assert not target.type_mask & M.POSITION_TARGET_TYPEMASK_FORCE_SET


def test_position_and_velocity_combine_per_axis() -> None:
    target = position_target(Setpoint(x=1, y=2, vz=-1))
    assert target.type_mask == (
        M.POSITION_TARGET_TYPEMASK_Z_IGNORE | M.POSITION_TARGET_TYPEMASK_VX_IGNORE
        | M.POSITION_TARGET_TYPEMASK_VY_IGNORE | 448 | 1024 | 2048
    )  # fmt: skip


def test_a_global_setpoint_is_global_int_relative_alt_in_degE7() -> None:
    target = position_target(Setpoint(frame="global", lat=47.3978, lon=8.5456, alt=10, yaw=0))
    assert isinstance(target, PositionTargetGlobal)
    assert (target.lat, target.lon, target.alt) == (473978000, 85456000, 10.0)
    assert target.type_mask == 56 | 448 | 2048
    m = wire(PositionTargetGlobal(500, target.type_mask, target.lat, target.lon, target.alt))
    assert m.get_type() == "SET_POSITION_TARGET_GLOBAL_INT"
    assert m.coordinate_frame == M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    assert (m.lat_int, m.lon_int, m.alt, m.type_mask) == (473978000, 85456000, 10.0, 56 | 448 | 2048)


def test_goto_is_do_reposition_with_change_mode_in_amsl_like_mavsdk_goto_location() -> None:
    c = goto_command(Goto(x=100, y=50, z=-20, speed=3, yaw=90), HOME)
    lat, lon = ned_to_geodetic(100.0, 50.0, HOME.lat, HOME.lon)
    assert (c.command, c.frame) == (M.MAV_CMD_DO_REPOSITION, M.MAV_FRAME_GLOBAL)
    assert c.params[:3] == (3.0, float(M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE), 0.0)
    assert c.params[3] == pytest.approx(math.pi / 2)  # PX4 reads param4 in radians
    assert (c.x, c.y, c.z) == (round(lat * 1e7), round(lon * 1e7), 508.0)
    m = wire(c)
    assert m.get_type() == "COMMAND_INT"
    assert (m.command, m.frame, m.x, m.y, m.z, m.target_system) == (192, 0, c.x, c.y, 508.0, 1)
    assert m.param2 == 1.0


def test_goto_defaults_and_global_points() -> None:
    c = goto_command(Goto(lat=47.4, lon=8.55, alt=12), HOME)
    assert c.params[0] == -1.0 and math.isnan(c.params[3])  # the vehicle's speed and yaw
    assert (c.x, c.y, c.z) == (474000000, 85500000, 500.0)


def test_orbit_is_do_orbit_with_signed_radius_and_an_optional_centre() -> None:
    c = orbit_command(Orbit(radius=10, velocity=2, x=0, y=0, z=-15), HOME)
    assert (c.command, c.frame) == (M.MAV_CMD_DO_ORBIT, M.MAV_FRAME_GLOBAL)
    assert c.params[:2] == (10.0, 2.0) and math.isnan(c.params[2]) and c.params[3] == 0.0
    assert (c.x, c.y, c.z) == (round(HOME.lat * 1e7), round(HOME.lon * 1e7), 503.0)
    here = orbit_command(Orbit(radius=5, clockwise=False), HOME)
    assert here.params[0] == -5.0 and math.isnan(here.params[1])
    assert (here.x, here.y) == (2**31 - 1, 2**31 - 1) and math.isnan(here.z)  # PX4: the current position


def test_land_start_yaw_and_fault_commands() -> None:
    assert land_start_command() == CommandLong(M.MAV_CMD_DO_LAND_START, (0.0,) * 7)
    y = yaw_command(YawCommand(heading=-90, rate=-20, direction="counterClockwise"))
    assert y.command == M.MAV_CMD_CONDITION_YAW and y.params[:4] == (270.0, 20.0, -1.0, 0.0)
    rel = yaw_command(YawCommand(heading=-45, relative=True))
    assert rel.params[:4] == (-45.0, 0.0, 0.0, 1.0)
    f = fault_command(Fault(at=3, unit="gps", type="off"))
    assert f.command == M.MAV_CMD_INJECT_FAILURE
    assert f.params[:3] == (M.FAILURE_UNIT_SENSOR_GPS, M.FAILURE_TYPE_OFF, 0.0)
    motor = fault_command(Fault(at=3, unit="motor", type="wrong", instance=2))
    assert motor.params[:3] == (M.FAILURE_UNIT_SYSTEM_MOTOR, M.FAILURE_TYPE_WRONG, 2.0)


# --------------------------------------------------------------------------- streaming


def setpoints(out: list[object]) -> list[PositionTargetLocal]:
    return [m for m in out if isinstance(m, PositionTargetLocal)]


def test_setpoints_stream_at_20_hz_and_mode_offboard_waits_half_a_second_of_them() -> None:
    s = CommandScheduler(
        [cmd(2, "setpoint", setpoint={"x": 0, "y": 0, "z": -5}), cmd(2, "mode", mode="offboard")]
    )
    out = s.update(2000, 0.0, armed=True)
    assert [type(m).__name__ for m in out] == ["PositionTargetLocal"]  # the mode waits
    assert out[0].time_ms == 2000 and out[0].z == -5.0
    assert s.next_event_ms == 2050  # the next setpoint (lockstep grants end there)
    assert s.update(2020, 0.0, armed=True) == []
    for t in range(2050, 2500, 50):
        out = s.update(t, 0.0, armed=True)
        assert len(setpoints(out)) == 1 and not any(isinstance(m, CommandLong) for m in out)
    out = s.update(2000 + OFFBOARD_WARMUP_MS, 0.0, armed=True)
    assert mode_command(FlightMode.OFFBOARD) in out and len(setpoints(out)) == 1
    s.handle_ack(CommandAck(Cmd.DO_SET_MODE, AckResult.ACCEPTED), 2500, 0.1)
    assert s.setpoint is not None  # offboard: keeps streaming
    assert [label for _, label in s.sent] == ["setpoint x=0,y=0,z=-5", "mode offboard"]


def test_a_new_setpoint_replaces_the_stream_at_once_and_mode_land_ends_it() -> None:
    s = CommandScheduler(
        [
            cmd(1, "setpoint", setpoint={"x": 0, "y": 0, "z": -5}),
            cmd(3, "setpoint", setpoint={"x": 10, "y": 0, "z": -5}),
            cmd(5, "mode", mode="land"),
        ]
    )
    s.update(1000, 0.0, armed=True)
    out = s.update(3000, 0.0, armed=True)
    assert [m.x for m in setpoints(out)] == [10.0]
    assert setpoints(s.update(3050, 0.0, armed=True))[0].x == 10.0
    out = s.update(5000, 0.0, armed=True)
    assert mode_command(FlightMode.LAND) in out
    s.handle_ack(CommandAck(Cmd.DO_SET_MODE, AckResult.ACCEPTED), 5000, 0.1)
    assert s.setpoint is None and setpoints(s.update(5100, 0.2, armed=True)) == []
    assert s.next_event_ms == math.inf


def test_a_refused_mode_switch_keeps_the_setpoints_and_a_disarm_ends_them() -> None:
    s = CommandScheduler(
        [
            cmd(1, "setpoint", setpoint={"vx": 1, "vy": 0, "vz": 0}),
            cmd(2, "mode", mode="hold"),
            cmd(3, "disarm"),
        ]
    )
    s.update(1000, 0.0, armed=True)
    s.update(2000, 0.0, armed=True)
    s.handle_ack(CommandAck(Cmd.DO_SET_MODE, AckResult.DENIED), 2000, 0.1)
    assert s.setpoint is not None
    out = s.update(3000, 0.2, armed=True)
    assert any(isinstance(m, CommandLong) and m.command == Cmd.COMPONENT_ARM_DISARM for m in out)
    assert s.setpoint is None


@pytest.mark.parametrize(
    ("command", "mav_cmd"),
    [
        (cmd(2, "goto", goto={"x": 5, "y": 5, "z": -5}), Cmd.DO_REPOSITION),
        (cmd(2, "orbit", orbit={"radius": 5}), Cmd.DO_ORBIT),
        (cmd(2, "land_start"), Cmd.DO_LAND_START),
    ],
)
def test_goto_orbit_and_land_start_leave_offboard_once_accepted(command: Command, mav_cmd: int) -> None:
    s = CommandScheduler([cmd(1, "setpoint", setpoint={"x": 0, "y": 0, "z": -5}), command], home=HOME)
    s.update(1000, 0.0, armed=True)
    out = s.update(2000, 0.0, armed=True)
    sent = [m for m in out if isinstance(m, CommandInt | CommandLong)]
    assert [m.command for m in sent] == [mav_cmd]
    s.handle_ack(CommandAck(mav_cmd, AckResult.ACCEPTED), 2000, 0.1)
    assert s.setpoint is None and s.idle


def test_mode_offboard_without_setpoints_is_sent_and_the_refusal_recorded() -> None:
    s = CommandScheduler([cmd(1, "arm"), cmd(2, "mode", mode="offboard")])
    s.update(1000, 0.0, armed=False)
    s.handle_ack(CommandAck(Cmd.COMPONENT_ARM_DISARM, AckResult.ACCEPTED), 1000, 0.0)
    assert s.update(2000, 0.1, armed=True) == [mode_command(FlightMode.OFFBOARD)]
    s.handle_ack(CommandAck(Cmd.DO_SET_MODE, AckResult.DENIED), 2000, 0.1)
    assert s.refusals[-1].label == "mode offboard" and s.error is None


def test_a_goto_is_resent_unchanged_on_silence() -> None:
    s = CommandScheduler([cmd(1, "goto", goto={"x": 5, "y": 5, "z": -5})], home=HOME)
    [first] = s.update(1000, 0.0, armed=True)
    assert s.update(1000, 1.5, armed=True) == [first]


# --------------------------------------------------------------------------- faults


def test_a_fault_goes_out_at_its_time_in_order_with_the_commands_and_its_ack_is_kept() -> None:
    s = CommandScheduler(
        [cmd(5, "mode", mode="land")],
        faults=[Fault(at=5, unit="gps", type="off"), Fault(at=3, unit="baro", type="stuck")],
    )
    assert s.update(2999, 0.0, armed=True) == []
    [baro] = s.update(3000, 0.0, armed=True)
    assert baro == fault_command(Fault(at=3, unit="baro", type="stuck"))
    s.handle_ack(CommandAck(Cmd.INJECT_FAILURE, AckResult.ACCEPTED), 3010, 0.1)
    [land] = s.update(5000, 0.2, armed=True)
    assert land == mode_command(FlightMode.LAND)  # the command first at equal times
    s.handle_ack(CommandAck(Cmd.DO_SET_MODE, AckResult.ACCEPTED), 5000, 0.2)
    [gps] = s.update(5000, 0.2, armed=True)
    assert gps.command == Cmd.INJECT_FAILURE and gps.params[0] == mav.FailureUnit.SENSOR_GPS
    s.handle_ack(CommandAck(Cmd.INJECT_FAILURE, AckResult.DENIED), 5020, 0.3)
    assert [(f.unit, f.type, f.sent_ms, f.ack_ms, f.result) for f in s.faults] == [
        ("baro", "stuck", 3000, 3010, "ACCEPTED"),
        ("gps", "off", 5000, 5020, "DENIED"),
    ]
    assert s.refusals[-1].label == "fault gps off" and s.error is None  # the vehicle refused: recorded
    assert s.faults[0].to_json()["at"] == 3.0


def test_a_fault_the_simulator_does_not_model_is_a_bench_error_saying_so() -> None:
    s = CommandScheduler([], faults=[Fault(at=1, unit="gps", type="off")], simulator="builtin")
    s.update(1000, 0.0, armed=True)
    s.handle_ack(CommandAck(Cmd.INJECT_FAILURE, AckResult.UNSUPPORTED), 1000, 0.0)
    assert s.error == (
        "the built-in simulator does not support failure injection of gps/off; "
        "fly this test with simulator: px4"
    )
    assert s.faults[0].result == "UNSUPPORTED"


def test_a_fault_nobody_answers_is_a_bench_error_not_a_silent_pass() -> None:
    s = CommandScheduler([], faults=[Fault(at=1, unit="gps", type="off")], send_attempts=2)
    s.update(1000, 0.0, armed=True)
    [again] = s.update(1000, 1.5, armed=True)
    assert again.confirmation == 1
    s.update(1000, 3.0, armed=True)
    assert s.error is not None and "no COMMAND_ACK for fault gps off" in s.error
    assert s.faults[0].result is None


def test_expand_labels() -> None:
    assert expand(Fault(at=1, unit="motor", type="off", instance=3))[0].label == "fault motor #3 off"
    assert (
        expand(cmd(1, "orbit", orbit={"radius": 5, "clockwise": False}))[0].label
        == "orbit r=5 counter-clockwise"
    )


# --------------------------------------------------------------------------- plan and core

SPEC = {
    "commands": [{"at": 1, "action": "arm"}],
    "faults": [{"at": 2, "unit": "gps", "type": "off"}],
}


def test_faults_enable_failure_injection_in_the_params_stage() -> None:
    spec = UavTestSpec.model_validate({**SPEC, "vehicle": {"params": {"MPC_XY_CRUISE": 5}}})
    assert flight_params(spec) == {"MPC_XY_CRUISE": 5, "SYS_FAILURE_EN": 1}
    plan = plan_flight(spec, endpoint="udpin:127.0.0.1:0")
    assert plan.params["SYS_FAILURE_EN"] == 1 and [f.unit.value for f in plan.faults] == ["gps"]
    assert plan.home == spec.world.home
    no_faults = UavTestSpec.model_validate({"commands": SPEC["commands"]})
    assert "SYS_FAILURE_EN" not in flight_params(no_faults)


def test_the_core_sets_sys_failure_en_injects_and_reports_the_fault() -> None:
    spec = UavTestSpec.model_validate(SPEC)
    cfg = plan_flight(spec, endpoint="udpin:127.0.0.1:0")
    core = ReplicaCore(cfg)
    vehicle = ScriptedVehicle(param_types={"SYS_FAILURE_EN": 6})
    core.start(0.0)
    exchange(core, vehicle, boot(), 0.0)
    assert vehicle.params["SYS_FAILURE_EN"] != 0
    exchange(core, vehicle, [LockstepAnnounce(2000)], 0.5)  # arm (due at 1 s), answered
    exchange(core, vehicle, [LockstepAnnounce(2050)], 0.6)  # then the fault
    inject = [c for c in vehicle.commands if c.command == Cmd.INJECT_FAILURE]
    assert len(inject) == 1 and inject[0].params[:2] == (4.0, 1.0)
    core._snapshot()
    assert [(f.unit, f.result) for f in core.report.faults] == [("gps", "ACCEPTED")]


def test_lockstep_grants_end_at_the_next_setpoint() -> None:
    spec = UavTestSpec.model_validate(
        {"commands": [{"at": 1, "action": "setpoint", "setpoint": {"x": 0, "y": 0, "z": -3}}]}
    )
    core = ReplicaCore(plan_flight(spec, endpoint="udpin:127.0.0.1:0"))
    vehicle = ScriptedVehicle()
    exchange(core, vehicle, boot(), 0.0)
    exchange(core, vehicle, [LockstepAnnounce(1000)], 0.1)
    assert vehicle.grants[-1].until_ms == 1050
    assert [m for m in vehicle.sent if isinstance(m, PositionTargetLocal)][-1].time_ms == 1000


# --------------------------------------------------------------------------- flight intent


@pytest.mark.parametrize(
    ("commands", "reason"),
    [
        (
            [{"at": 1, "action": "arm"}, {"at": 2, "action": "goto", "goto": {"x": 1, "y": 1, "z": -5}}],
            "goto at t=2 s",
        ),
        (
            [{"at": 1, "action": "arm"}, {"at": 2, "action": "orbit", "orbit": {"radius": 5}}],
            "orbit at t=2 s",
        ),
        (
            [
                {"at": 1, "action": "arm"},
                {"at": 2, "action": "setpoint", "setpoint": {"x": 0, "y": 0, "z": -5}},
                {"at": 2, "action": "mode", "mode": "offboard"},
            ],
            "mode offboard at t=2 s",
        ),
        (
            [
                {"at": 1, "action": "arm"},
                {"at": 2, "action": "setpoint", "setpoint": {"x": 0, "y": 0, "z": -5}},
            ],
            None,
        ),
        ([{"at": 2, "action": "goto", "goto": {"x": 1, "y": 1, "z": -5}}], None),  # never armed
        ([{"at": 1, "action": "arm"}, {"at": 2, "action": "yaw", "yaw": {"heading": 90}}], None),
    ],
)
def test_flight_intent_of_offboard_goto_and_orbit(
    commands: list[dict[str, object]], reason: str | None
) -> None:
    assert flight_intent(UavTestSpec.model_validate({"commands": commands})) == reason


def test_faults_go_into_result_json() -> None:
    from uavtest.analysis.models import ReplicaResult, Verdict
    from uavtest.runner.commands import FaultRecord
    from uavtest.runner.core import FlightReport
    from uavtest.runner.main import injected_faults

    report = FlightReport(faults=[FaultRecord("gps", "off", 0, 20.0, 20_000, 20_004, "ACCEPTED")])
    result = ReplicaResult(index=0, seed=0, verdict=Verdict.PASS, faults=injected_faults(report))
    dumped = result.model_dump(mode="json")["faults"]
    assert dumped == [
        {
            "unit": "gps",
            "type": "off",
            "instance": 0,
            "at": 20.0,
            "sent_ms": 20000,
            "ack_ms": 20004,
            "result": "ACCEPTED",
        }
    ]
