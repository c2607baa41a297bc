"""Determinism gate: the built-in vehicle, fed the same messages at the same vehicle times with
the same seed, writes the same ULog bytes and sends the same MAVLink messages, bit for bit.

Each scenario drives ``Vehicle`` in-process and hashes (sha256) the ULog bytes written and the
sequence of messages returned by ``receive`` / ``advance`` / ``drain`` (name + sorted fields
repr). The constants were recorded from the code before the simulator was split into PX4-named
modules; a refactor must keep them identical. They are re-recorded only when behaviour changes
on purpose, and the commit that does so says why.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Iterable

import pytest

from uavtest.sitl.mav import MavCmd, Msg
from uavtest.sitl.mission import from_spec
from uavtest.sitl.params import encode_param_value
from uavtest.sitl.recorder import MemorySink
from uavtest.sitl.vehicle import SimConfig, Vehicle
from uavtest.spec.models import BoxPosition, BoxSize, Home, MissionItem, MissionItemKind, Obstacle, Wind

GCS = (255, 190)
HOME = Home()
SLICE_US = 20_000


class Harness:
    def __init__(self, config: SimConfig) -> None:
        self.sink = MemorySink()
        self.v = Vehicle(config, self.sink)
        self.h = hashlib.sha256()
        self.count = 0

    def _take(self, msgs: Iterable[Msg]) -> list[Msg]:
        out = list(msgs)
        for m in out:
            self.h.update(f"{m.name}{sorted(m.fields.items())!r}\n".encode())
            self.count += 1
        return out

    def send(self, name: str, fields: dict[str, object]) -> list[Msg]:
        return self._take(self.v.receive(Msg(name, fields, *GCS)))

    def command(self, cmd: int, *params: float, name: str = "COMMAND_LONG") -> int:
        fields: dict[str, object] = {"command": int(cmd), "target_system": 1, "target_component": 1}
        fields.update({f"param{i}": p for i, p in enumerate(params, start=1)})
        return int(self.send(name, fields)[0].fields["result"])

    def sticks(self, x: int, y: int, z: int, r: int) -> None:
        self.send("MANUAL_CONTROL", {"target": 1, "x": x, "y": y, "z": z, "r": r, "buttons": 0})

    def fly(self, seconds: float, until: Callable[[Vehicle], bool] | None = None, each=None) -> None:
        limit = self.v.time_us + int(seconds * 1e6)
        while self.v.time_us < limit:
            if until is not None and until(self.v):
                return
            if each is not None:
                each()
            self._take(self.v.advance(self.v.time_us + SLICE_US))
            self._take(self.v.drain())

    def digest(self) -> tuple[str, str]:
        self._take(self.v.drain())
        self.v.recorder.stop()
        ulog = hashlib.sha256(b"".join(self.sink.logs)).hexdigest()
        return ulog, self.h.hexdigest()


def _mission_items(alt: float = 5.0) -> list[MissionItem]:
    return [
        MissionItem(kind=MissionItemKind.TAKEOFF, lat=HOME.lat, lon=HOME.lon, alt=alt),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=HOME.lat + 0.0002, lon=HOME.lon, alt=alt),
        MissionItem(kind=MissionItemKind.WAYPOINT, lat=HOME.lat + 0.0002, lon=HOME.lon + 0.0002, alt=alt + 3),
        MissionItem(kind=MissionItemKind.LAND, lat=HOME.lat, lon=HOME.lon + 0.0002, alt=0),
    ]


def mission() -> tuple[str, str]:
    s = Harness(SimConfig(home=HOME, wind=Wind(mean_speed=2, max_speed=5, direction=45), seed=11))
    s.v.load_mission(from_spec(_mission_items()))
    s.fly(5, until=lambda v: v.ready)
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    s.command(MavCmd.DO_SET_MODE, 1, 4, 4)
    s.fly(180, until=lambda v: not v.armed)
    return s.digest()


def manual_and_rtl() -> tuple[str, str]:
    s = Harness(SimConfig(home=HOME, seed=23))
    s.send("HEARTBEAT", {"type": 6, "autopilot": 8})
    s.fly(5, until=lambda v: v.ready)
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    s.command(MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME.alt + 6)
    s.fly(30, until=lambda v: v.nav_state == 4 and not v.landed)
    s.sticks(0, 0, 500, 0)  # manual control first: PX4 refuses Position mode without it
    s.command(MavCmd.DO_SET_MODE, 1, 3, 0)  # POSCTL
    s.fly(4, each=lambda: s.sticks(600, 200, 500, 100))
    s.command(MavCmd.DO_SET_MODE, 1, 2, 0)  # ALTCTL
    s.fly(3, each=lambda: s.sticks(-300, 0, 700, -200))
    s.send("SET_MODE", {"target_system": 1, "base_mode": 1, "custom_mode": 3 << 16})
    s.fly(2, each=lambda: s.sticks(0, -400, 500, 0))
    s.fly(5)  # sticks stop: RC loss failsafe (NAV_RCL_ACT 2 = return)
    s.command(MavCmd.NAV_RETURN_TO_LAUNCH)
    s.fly(90, until=lambda v: not v.armed)
    return s.digest()


def datalink_loss() -> tuple[str, str]:
    s = Harness(SimConfig(home=HOME, params={"NAV_DLL_ACT": 3, "COM_DL_LOSS_T": 3}, seed=5))
    s.send("HEARTBEAT", {"type": 6, "autopilot": 8})
    s.fly(5, until=lambda v: v.ready)
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    s.command(MavCmd.NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, HOME.alt + 4)
    s.fly(60, until=lambda v: not v.armed)
    return s.digest()


def crash() -> tuple[str, str]:
    box = Obstacle(size=BoxSize(l=4, w=20, h=30), position=BoxPosition(x=15, y=0, z=0, r=0))
    s = Harness(SimConfig(home=HOME, obstacles=(box,), seed=3))
    s.v.load_mission(from_spec(_mission_items(alt=8)))
    s.fly(5, until=lambda v: v.ready)
    s.command(MavCmd.MISSION_START, 0, 0)
    s.fly(80, until=lambda v: not v.armed)
    s.fly(1)
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)  # denied: crashed
    return s.digest()


def params_and_commands() -> tuple[str, str]:
    s = Harness(SimConfig(home=HOME, params={"MPC_XY_VEL_MAX": 8.0}, seed=99))
    s.send("TIMESYNC", {"tc1": 0, "ts1": 12345})
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)  # not ready yet
    s.fly(5, until=lambda v: v.ready)
    s.send("PARAM_REQUEST_LIST", {"target_system": 1, "target_component": 1})
    s.send("PARAM_REQUEST_READ", {"param_id": "MIS_TAKEOFF_ALT", "param_index": -1})
    s.send("PARAM_SET", {"param_id": "MIS_TAKEOFF_ALT", "param_value": 4.0, "param_type": 9})
    s.send("PARAM_SET", {"param_id": "NAV_RCL_ACT", "param_value": encode_param_value(3, 6), "param_type": 6})
    s.send("PARAM_SET", {"param_id": "MPC_XY_CRUISE", "param_value": 3.0, "param_type": 9})
    s.command(MavCmd.SET_MESSAGE_INTERVAL, 32, 100_000)
    s.command(MavCmd.REQUEST_MESSAGE, 242)
    s.command(MavCmd.REQUEST_MESSAGE, 148)
    s.command(MavCmd.REQUEST_MESSAGE, 9999)
    s.command(MavCmd.REQUEST_AUTOPILOT_CAPABILITIES, 1)
    s.command(31010)  # unsupported
    s.command(183, 1, 1500)  # DO_SET_SERVO: unsupported
    s.command(MavCmd.DO_SET_MODE, 0, 4, 4)  # no custom flag: denied
    s.command(MavCmd.DO_SET_MODE, 1, 4, 4)  # no mission, disarmed: accepted (PX4 v1.15) ...
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)  # ... and arming in it refused
    s.command(MavCmd.DO_SET_MODE, 1, 6, 0)  # offboard while disarmed: accepted (PX4 v1.15)
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)  # in offboard without setpoints: refused
    s.command(MavCmd.DO_SET_MODE, 1, 4, 3)  # back to hold
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    s.fly(2)
    s.command(MavCmd.COMPONENT_ARM_DISARM, 0)  # still landed: accepted
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    s.send(
        "COMMAND_INT",
        {
            "command": int(MavCmd.NAV_TAKEOFF),
            "target_system": 1,
            "target_component": 1,
            "param4": math.nan,
            "x": 0,
            "y": 0,
            "z": HOME.alt + 3,
        },
    )
    s.fly(20, until=lambda v: v.nav_state == 4 and not v.landed)
    s.command(MavCmd.DO_CHANGE_SPEED, 1, 2.5)
    s.command(MavCmd.COMPONENT_ARM_DISARM, 0)  # in air: denied
    s.command(MavCmd.NAV_LAND)
    s.fly(40, until=lambda v: not v.armed)
    s.command(MavCmd.COMPONENT_ARM_DISARM, 1)
    s.fly(15)  # auto preflight disarm
    return s.digest()


SCENARIOS: dict[str, Callable[[], tuple[str, str]]] = {
    "mission": mission,
    "manual_and_rtl": manual_and_rtl,
    "datalink_loss": datalink_loss,
    "crash": crash,
    "params_and_commands": params_and_commands,
}

#: (ulog sha256, messages sha256) per scenario; re-recorded for issue 10's PX4-like flight (smooth
#: EKF2-like estimator error, FlightTaskAuto heading lock inside NAV_ACC_RAD, move-to-land altitude)
#: and for Collision Prevention (new ULog formats obstacle_distance(_fused), collision_constraints,
#: distance_sensor and the CP_* / MPC_POS_MODE parameters in the header) and COM_OBS_AVOID (a
#: modelled parameter now: one more in the header and the parameter list); and for PX4 SIH's
#: physics (SIH_KDV drag held by the velocity integrator), EKF2's velocity bias and
#: FlightTaskAuto's track states (offtrack) with PX4's braking distance (2026-11-24); and for
#: EKF2's velocity error calibrated on PX4 SIH's ground truth (stationary, 0.22 m/s, 4 s) and
#: waypoints accepted without a heading wait unless the item sets one (param4), and a mission
#: takeoff without a heading turning to face its takeoff point once drifted past NAV_ACC_RAD
#: (FlightTaskAuto's MPC_YAW_MODE 0) (2026-11-25); and for the landing descent tracking its
#: integrated z trajectory (PositionSmoothing) and the land detector's hysteresis steps of
#: LNDMC_TRIG_TIME / 3 after touchdown; and for PositionSmoothing's turn: the speed held while
#: the trajectory is not aligned with its target, aiming at the L1 point; and for EKF2's vertical
#: velocity bias (0.12 m/s) and the range finder's true height in dist_bottom; and for the
#: landing's jerk-limited vertical speed (MPC_JERK_AUTO) (2026-11-25, later); and for the velocity
#: loop's derivative term (MPC_XY_VEL_D_ACC on the velocity's MPC_VELD_LP-filtered derivative);
#: and for PositionSmoothing's per-axis VelocitySmoothing (time-optimal, jerk-limited, x and y
#: synchronized) and mission corners turned at computeMaxSpeedInWaypoint's speed (MPC_XY_TRAJ_P);
#: and for EKF2's heading error calibrated on PX4 SIH's ground truth (2.4 +- 2.6 degrees per flight,
#: 2.2 within), leaning the real thrust against it; and for PX4 SIH's attitude response (the tilt
#: 0.10 s after the thrust setpoint, then a 0.06 s lag, as all nine SIH logs show), FlightTaskAuto's
#: offtrack state in 3-D, the triplet's previous and next, vehicle_local_position_setpoint and the
#: ground truth (vehicle_local_position_groundtruth, vehicle_attitude_groundtruth) logged, and
#: LNDMC_XY_VEL_MAX modelled (the land detector judges movement on the estimate) (2026-11-25,
#: later); and for EKF2's altitude shift after touchdown (range finder below its minimum, 16 PX4
#: SIH flights with ground truth), the frozen terrain estimate (dist_bottom, its 5 s validity, the
#: land detector's "close to ground" and hysteresis factor 3) and z_deriv logged (2026-11-26);
#: and for EKF2's horizontal estimate leading the truth by 0.10 s of its velocity (its velocity
#: by 0.03 s of the acceleration; EKF2_GPS_DELAY against SIH's undelayed GPS; not with the local
#: planner's Gazebo, whose GPS plugin delays); the logs again (the MAVLink streams unchanged) for
#: dist_bottom logged as the land detector sees it after touchdown (0.1 m below the frozen terrain
#: estimate, EKF2's on-ground distance, not the true 0); and for EKF2's horizontal velocity error
#: driven by body-frame noise, larger sideways than fore-aft as SIH's accelerometer noise is
#: (0.17 / 0.26 m/s along the body's x / y axis in 16 PX4 SIH flights) (2026-11-26, later); and
#: for PX4 SIH's body fixed by its parameters (no drag or tilt-response spread between replicas)
#: and its yaw setpoint swept at exactly MPC_YAWRAUTO_MAX (2026-11-26, stop 21); and for PX4's
#: hover thrust estimator (mc_hover_thrust_estimator: SIH's thrust against the estimate
#: PositionControl flies with, PositionControl's horizontal anti-windup, the
#: hover_thrust_estimate topic, HTE_* / MPC_USE_HTE in the parameter list and the thrust setpoint's
#: horizontal part scaled as PX4's decoupled one; the anti-windup in position mode too) (2026-11-26,
#: stop 21); the logs again (the MAVLink streams unchanged) for vehicle_local_position_setpoint's
#: velocity logged as PositionControl's _vel_sp (the trajectory's velocity plus MPC_XY_P / MPC_Z_P
#: times the position error), as PX4 logs it (stop 22); and for PX4's yaw chain (FlightTaskAuto's
#: setpoint slew at MPC_YAWRAUTO_MAX without an acceleration limit and its filtered feed-forward,
#: mc_att_control's MC_YAW_P law, mc_rate_control's yaw PI and SIH's yaw torque, damping and
#: allocation headroom), and the manual modes' StickYaw (MPC_MAN_Y_TAU, in the parameter list: the
#: parameter streams too) and heading lock; and for EKF2's heading error low-passed at 0.3 s (as
#: smooth as PX4 SIH's logged heading) (stop 22); the logs again (the flight and the MAVLink
#: streams unchanged) for vehicle_land_detected published when ground contact or maybe landed
#: changes, as PX4's land detector does, not only on landed or at 1 Hz (stop 23); and the
#: mission's flight for FlightTaskAuto's track states judged in the horizontal plane, as PX4 has
#: since v1.13 (Vector2f; the offtrack point at the target's altitude) (stop 23); and every
#: scenario for PositionSmoothing in three axes (the velocity setpoint straight at the 3-D target,
#: z's own jerk-limited profile synchronized with x and y), the takeoff's PX4 constraints (its
#: jerk-limited approach below MPC_LAND_ALT1, a waypoint's above) and PositionControl's vertical
#: acceleration feed-forward (stop 23); manual_and_rtl again for the track from where the vehicle
#: was when a triplet without a previous waypoint arrived (its return leg), as FlightTaskAuto's
#: _evaluateTriplets sets _triplet_prev_wp (stop 23); manual_and_rtl and params_and_commands for
#: the auto modes' climb-rate limits (MulticopterPositionControl's setVelocityLimits) and the
#: landing speed's PX4 parameters (MPC_Z_VEL_MAX_DN, MPC_Z_V_AUTO_DN's cap, MPC_LAND_CRWL) (stop 23);
#: params_and_commands again for MIS_TAKEOFF_ALT as Takeoff's default, not a minimum, and the
#: cruise speed reset on every navigator mode's activation, as PX4 v1.15's navigator does (stop 23);
#: every log for NAV_LOITER_RAD, now modelled, moved among the parameters (their order; the
#: flights' telemetry is unchanged), params_and_commands' telemetry too (PARAM_VALUE indices).
#: mission, manual_and_rtl, datalink_loss and params_and_commands for PX4 v1.15's commander timing:
#: the auto-disarm COM_DISARM_LAND after landing in Return / Land (one tick after the mission has
#: finished for a mission armed on the ground: handleAutoDisarm's hysteresis), and the RC and data
#: link failsafes held COM_FAIL_ACT_T in Hold first, with PX4's texts (failsafe framework).
#: stop 24, both together: the failsafe's Hold (COM_FAIL_ACT_T) now holds at the braking stop.
#: every scenario's log header for RTL_CONE_ANG modelled (one more parameter; every logged topic and
#: log message byte-identical, pyulog), params_and_commands' parameter list for it too, and
#: manual_and_rtl's return as rtl_direct.cpp flies it (climb where Return started facing its
#: heading, descent and landing turned to home's heading, "RTL: start return at N m (M m above
#: destination)", "RTL: land at destination") (RTL cone branch).
#: stop 24, all three together: the commander gives the navigator home's heading (home_position.yaw).
#: stop 25: COM_RC_OVERRIDE and COM_RC_STICK_OV modelled (two more parameters in every header and in
#: params_and_commands' parameter list) and manual_control_setpoint.sticks_moving as PX4's
#: ManualControl computes it (a low-passed stick rate above COM_RC_STICK_OV, manual_and_rtl); every
#: other logged field and every log message byte-identical (pyulog), no flight changed.
#: stop 25, then: PX4's position mode (MPC_POS_MODE 4, StickAccelerationXY) and the sticks' deadzone
#: and expo (MPC_XY_MAN_EXPO, MPC_Z_MAN_EXPO, MPC_YAW_EXPO; five more parameters in every header and
#: in params_and_commands' list): manual_and_rtl's hand-flown part flies differently; mission,
#: datalink_loss and crash have every logged field byte-identical (pyulog). Then altitude mode's
#: tilt as PX4's StickTiltXY (raw stick x tan(MPC_MAN_TILT_MAX) g): manual_and_rtl only.
#: stop 26: PX4 v1.15's mode requirements (COM_ARM_MIS_REQ modelled: one more parameter in every
#: header and in params_and_commands' list): mission's logged fields byte-identical (pyulog);
#: datalink_loss and crash differ only in vehicle_status after the disarm (PX4's onDisarm: back in
#: the user's last mode that may arm, no failsafe action disarmed); manual_and_rtl sends its sticks
#: before Position mode (PX4 refuses it without manual control) and says "Returning to launch";
#: params_and_commands' Mission without a mission is taken disarmed and arming in it refused
#: ("Arming denied: Resolve system health failures first", as in Offboard), and after landing it
#: arms again in Hold (it stayed in Land before, a mode PX4 does not arm in).
#: stop 27: PX4's mission FeasibilityChecker (MIS_DIST_1WP now modelled, MIS_TKO_LAND_REQ stored
#: when first read, as PX4 lists it once used: the parameter lists change) and waypoints reached
#: only in the air; with the parameter table as before, every hash was unchanged: no flight changed.
#: stop 28: a takeoff has FlightTaskAuto's track (from where the vehicle was when the triplet came
#: to the point the navigator took a sample earlier): mission's and crash's takeoffs start
#: from a point a control tick behind (the navigator's sample), and their flights move by it.
#: Then EKF2's heading error settles during the first leg (a climb offset, then the flight's,
#: ekf2.HEADING_SETTLE_TAU): every scenario's heading error, so every flight, changes.
#: stop 29: body rates (``Body.rates``) in ATTITUDE, ATTITUDE_QUATERNION, ODOMETRY and HIGHRES_IMU
#: (zeros for roll and pitch before) and a new logged topic, vehicle_angular_velocity: every hash
#: changes; no flight does (vehicle_local_position of the three competition missions, 3 seeds each,
#: array-identical before and after).
#: Then EKF2's horizontal velocity error low-passed (ekf2.VELOCITY_SMOOTH_S, as smooth as PX4 SIH's
#: against its ground truth): the velocity estimate, so every flight, changes.
#: Then EKF2's heading error after the first leg's start as PX4 SIH's (a delayed rise toward a
#: decaying target, ekf2.HEADING_PEAK / HEADING_DECAY_TAU): every flight that moves, changes.
#: Then the logged land setpoint's altitude as PX4's navigator sets it (Goal.alt_amsl): the ULog of
#: every scenario that lands changes (mission, manual_and_rtl, datalink_loss); every message hash,
#: crash's and params_and_commands' ULog unchanged.
#: stop 30: EKF2's velocity misses part of the true acceleration and its heading error turns the
#: rest sideways (ekf2.ACC_COUPLING, HEADING_COUPLING: PX4 SIH's braking into a waypoint against
#: its ground truth): mission, manual_and_rtl, crash and params_and_commands change; datalink_loss
#: (a hover) is byte-identical.
#: 2026-11-27: every ULog hash re-recorded, every message hash unchanged (no flight changed):
#: what a control tick logs carries the tick's time (mission_result was stamped at the start of
#: the clock's slice) and position_setpoint_triplet is logged the tick it changes, not at the next
#: 10 Hz sample.
#: Then EKF2's horizontal velocity bias second order (ekf2.TAU_BIAS_XY, SIGMA_BIAS_XY, PX4 SIH's
#: velocity error gone within 5 s) and less smoothing (VELOCITY_SMOOTH_S 0.08): every scenario's
#: estimate, so every flight, changes.
#: Then the attitude is the thrust setpoint's direction through the attitude loops, its vertical part
#: too (``Body.azt``): every logged and streamed attitude and body rate changes; no flight does.
#: Then the attitude loops as PX4 SIH's fit in 24 flights (ATTITUDE_DELAY 0.08, TAU_TILT 0.09) and
#: VELOCITY_SMOOTH_S 0.04: every flight changes
#: stop 32: vehicle_local_position(_groundtruth)'s ax, ay, az are the kinematic acceleration (thrust,
#: drag and gravity), as EKF2 and SIH log them, not the thrust's alone: every ULog; HIGHRES_IMU takes
#: it from the physics step (the drag at that step's velocity and wind), so every message hash but
#: datalink_loss's moves in HIGHRES_IMU's last bits; no flight changes
#: (vehicle_local_position's x, y, z, v, heading hash-equal on missions 1-3, two seeds)
#: Then EKF2's heading error recalibrated on two sets of 24 PX4 SIH flights (a flight keeps its shift:
#: HEADING_FLIGHT_SPREAD 3.6, HEADING_CLIMB_FLIGHT_CORR -0.45, SIGMA_HEADING 2.0, HEADING_DECAY_TAU
#: 22): every scenario's heading, so every flight, changes (the local planner's system keeps its
#: process, GAZEBO_SIGMA_HEADING: its flights hash-equal)
#: stop 33: PX4's vertical control in PX4 SIH's system: TakeoffHandling's ramp (the upward limit
#: from -g / MPC_Z_VEL_P_ACC), PositionControl's integrator at MPC_Z_VEL_I_ACC with its anti-windup,
#: SIH's ground letting go at thrust = weight (``Body.liftoff_acc`` 0): every scenario's takeoff and
#: altitude hold, so every flight, changes
#: Then the same ramp for a takeoff from the ground in the stick modes (altitude, position) and
#: offboard (``Controller.tko_ramp_s``, restarted while the vehicle idles landed): no scenario takes
#: off with the sticks, every hash unchanged
#: stop 34: PX4 SIH's lift-off kick (``simulator_sih.KICK_GAIN``): the ground holds the body level
#: and PX4's rate integrators wind up against it while the land detector says neither landed nor
#: maybe landed; the body is let go with them: every scenario's takeoff, so every flight, changes.
#: Then the body rates (ATTITUDE, vehicle_angular_velocity) with the kick's turn: every log and
#: telemetry hash changes, the flights (vehicle_local_position) do not
#: stop 34, then: EKF2's altitude drift in flight (``ekf2.HGT_*``: a damped oscillator, 0.5 m, in
#: the estimated altitude and climb rate, frozen from touchdown): every scenario's flight changes
#: stop 36: EKF2's tilt error (``ekf2.TILT_*``: the estimated roll and pitch off the truth, growing
#: while armed on the ground, the body leaning the other way, the push partly unseen by the
#: velocity estimate), with the velocity bias and its body-frame noise recalibrated so the whole
#: velocity error stays PX4's: every scenario's flight and attitude changes
#: stop 37: the horizontal velocity bias correlated longer (``ekf2.TAU_BIAS_XY`` 1.2 -> 1.6 s, its
#: spread 0.14 -> 0.13 m/s): every scenario's flight changes
#: stop 39: EKF2's position follows half the tilt push it misses (``ekf2.TILT_POSITION_SHARE``,
#: part of the lift-off's kept out), the push balanced slower (``TILT_BALANCE_TAU`` 2 -> 8 s), the
#: bias smaller at rest (``SIGMA_BIAS_XY`` 0.13 -> 0.08 m/s) and growing sideways with the speed
#: (``BIAS_SPEED_GAIN``): every scenario's flight changes
#: stop 40: EKF2's miss of the acceleration leaks faster and is bounded (``ekf2.ACC_COUPLING``
#: 0.1 -> 0.37, ``ACC_COUPLING_TAU`` 2 -> 0.6 s, ``HEADING_COUPLING`` 1.0 -> 3.3,
#: ``ACC_COUPLING_MAX`` 0.9 m/s^2): every scenario's flight changes
#: stop 42: the sideways bias stops growing above 4 m/s (``ekf2.BIAS_SPEED_MAX`` 6 -> 4): the
#: mission scenario, the one flown faster than 4 m/s, changes
#: stop 45: EKF2's tilt error while armed on the ground smaller (``ekf2.TILT_SIGMA_ARMED`` 2.3 ->
#: 1.75 degrees) and the lift-off kick weaker (``simulator_sih.KICK_GAIN`` 2.5 -> 2.0), both measured
#: again on 96 PX4 SIH flights (``analysis.liftoff``): every scenario's takeoff, so every flight,
#: changes
GOLDEN: dict[str, tuple[str, str]] = {
    "mission": (
        "14a6e448f3aee2893cc0dd9f2d9748f6c8cec006eba65e1e060cd4c0aef7bf7e",
        "12d02c74f76d05a425124631f5893e5937c7e0e61c6805c23afcee24dc3f119c",
    ),
    "manual_and_rtl": (
        "bf928725edfc4d859390ca0606e4acb983fc7deab5e5160286a2b5c7a49706a7",
        "befbd2a6895f468febbec0d42493d9799621074a42ca949b6b8b8c2f77e7db76",
    ),
    "datalink_loss": (
        "72d07ec6fab82163edaa5e3eaa3edbc2a41b05a95e22a8af5672e235095d62f2",
        "e8a9ba2c917f1028307e8f4698f7a5d49be2e60fb956193809efeb10e49f0fed",
    ),
    "crash": (
        "94d36e0df1b4d091c2bab28b96336554084dd6eaf19c87d07bd21ba7698c18cb",
        "4fed88bcb6de330b2ca8dc15970d74d1930bd1d193d3751692bd2c5971b5b9ad",
    ),
    "params_and_commands": (
        "7e0be051942e80e4c3065eb07aba74a692459a5b654e42aa1b22ce91417e3ce5",
        "19ba4431ddaf5f01efa1ea35ed79649d67887a532bba288f3ca5d4938cc5a1ce",
    ),
}


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_same_seed_same_bytes(name: str) -> None:
    assert SCENARIOS[name]() == GOLDEN[name]


if __name__ == "__main__":  # print the current hashes (re-recording, with a reason)
    for key, fn in SCENARIOS.items():
        print(f'    "{key}": {fn()!r},')
