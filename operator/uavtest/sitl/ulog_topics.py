"""PX4 uORB topics as this simulator logs them: ULog formats and record builders.

Names, field names and types follow PX4 v1.15's ``msg/*.msg`` (a subset of fields, in PX4's
order), so ``pyulog`` and the analysis read our logs exactly like PX4's: e.g.
``position_setpoint_triplet`` nests three ``position_setpoint`` and reads back as
``current.lat``, ``next.valid`` and so on. Each builder returns the flat value tuple of one record.
"""

from __future__ import annotations

import math

__all__ = ["FORMATS", "TOPICS", "Setpoint", "command", "local_position", "quaternion"]

FORMATS: dict[str, list[str]] = {
    "position_setpoint": [
        "uint64_t timestamp",
        "double lat",
        "double lon",
        "float vx",
        "float vy",
        "float vz",
        "float alt",
        "float yaw",
        "float loiter_radius",
        "float acceptance_radius",
        "float cruising_speed",
        "float cruising_throttle",
        "bool valid",
        "uint8_t type",
        "bool loiter_direction_counter_clockwise",
        "bool gliding_enabled",
    ],
    "vehicle_local_position": [
        "uint64_t timestamp",
        "uint64_t timestamp_sample",
        "float x",
        "float y",
        "float z",
        "float vx",
        "float vy",
        "float vz",
        "float z_deriv",
        "float ax",
        "float ay",
        "float az",
        "float heading",
        "float delta_heading",
        "float dist_bottom",
        "float eph",
        "float epv",
        "float evh",
        "float evv",
        "double ref_lat",
        "double ref_lon",
        "float ref_alt",
        "uint64_t ref_timestamp",
        "float vxy_max",
        "float vz_max",
        "float hagl_min",
        "float hagl_max",
        "bool xy_valid",
        "bool z_valid",
        "bool v_xy_valid",
        "bool v_z_valid",
        "bool xy_global",
        "bool z_global",
        "bool dist_bottom_valid",
        "bool heading_good_for_control",
        "bool dead_reckoning",
    ],
    "vehicle_global_position": [
        "uint64_t timestamp",
        "uint64_t timestamp_sample",
        "double lat",
        "double lon",
        "float alt",
        "float alt_ellipsoid",
        "float eph",
        "float epv",
        "float terrain_alt",
        "bool terrain_alt_valid",
        "bool dead_reckoning",
    ],
    "vehicle_attitude": [
        "uint64_t timestamp",
        "uint64_t timestamp_sample",
        "float[4] q",
        "float[4] delta_q_reset",
        "uint8_t quat_reset_counter",
    ],
    "vehicle_status": [
        "uint64_t timestamp",
        "uint64_t armed_time",
        "uint64_t takeoff_time",
        "uint64_t nav_state_timestamp",
        "uint8_t arming_state",
        "uint8_t latest_arming_reason",
        "uint8_t latest_disarming_reason",
        "uint8_t nav_state_user_intention",
        "uint8_t nav_state",
        "uint16_t failure_detector_status",
        "uint8_t hil_state",
        "uint8_t vehicle_type",
        "bool failsafe",
        "bool gcs_connection_lost",
        "uint8_t system_type",
        "uint8_t system_id",
        "uint8_t component_id",
        "bool pre_flight_checks_pass",
    ],
    "vehicle_land_detected": [
        "uint64_t timestamp",
        "bool freefall",
        "bool ground_contact",
        "bool maybe_landed",
        "bool landed",
        "bool in_ground_effect",
        "bool in_descend",
        "bool has_low_throttle",
        "bool vertical_movement",
        "bool horizontal_movement",
        "bool close_to_ground_or_skipped_check",
        "bool at_rest",
    ],
    "actuator_armed": [
        "uint64_t timestamp",
        "bool armed",
        "bool prearmed",
        "bool ready_to_arm",
        "bool lockdown",
        "bool manual_lockdown",
        "bool force_failsafe",
    ],
    "vehicle_command": [
        "uint64_t timestamp",
        "double param5",
        "double param6",
        "float param1",
        "float param2",
        "float param3",
        "float param4",
        "float param7",
        "uint32_t command",
        "uint8_t target_system",
        "uint8_t target_component",
        "uint8_t source_system",
        "uint16_t source_component",
        "uint8_t confirmation",
        "bool from_external",
    ],
    "vehicle_command_ack": [
        "uint64_t timestamp",
        "uint32_t command",
        "uint8_t result",
        "uint8_t result_param1",
        "int32_t result_param2",
        "uint8_t target_system",
        "uint16_t target_component",
        "bool from_external",
    ],
    "position_setpoint_triplet": [
        "uint64_t timestamp",
        "position_setpoint previous",
        "position_setpoint current",
        "position_setpoint next",
    ],
    "mission_result": [
        "uint64_t timestamp",
        "uint32_t mission_id",
        "uint32_t geofence_id",
        "uint32_t home_position_counter",
        "int32_t seq_reached",
        "uint16_t seq_current",
        "uint16_t seq_total",
        "bool valid",
        "bool warning",
        "bool finished",
        "bool failure",
        "uint16_t item_do_jump_changed",
        "uint16_t item_changed_index",
        "uint16_t item_do_jump_remaining",
        "uint8_t execution_mode",
    ],
    "manual_control_setpoint": [
        "uint64_t timestamp",
        "uint64_t timestamp_sample",
        "bool valid",
        "uint8_t data_source",
        "float roll",
        "float pitch",
        "float yaw",
        "float throttle",
        "float flaps",
        "float aux1",
        "float aux2",
        "bool sticks_moving",
        "uint16_t buttons",
    ],
    "home_position": [
        "uint64_t timestamp",
        "double lat",
        "double lon",
        "float alt",
        "float x",
        "float y",
        "float z",
        "float yaw",
        "bool valid_alt",
        "bool valid_hpos",
        "bool valid_lpos",
        "bool manual_home",
        "uint32_t update_count",
    ],
    "trajectory_setpoint": [
        "uint64_t timestamp",
        "float[3] position",
        "float[3] velocity",
        "float[3] acceleration",
        "float yaw",
        "float yawspeed",
    ],
}

#: topics subscribed in every log, in this order
TOPICS = [name for name in FORMATS if name != "position_setpoint"]

NAN = math.nan

# position_setpoint.type
SETPOINT_TYPE_POSITION = 0
SETPOINT_TYPE_LOITER = 2
SETPOINT_TYPE_TAKEOFF = 3
SETPOINT_TYPE_LAND = 4
SETPOINT_TYPE_IDLE = 5

Setpoint = tuple[object, ...]
INVALID_SETPOINT: Setpoint = (
    0,
    NAN,
    NAN,
    NAN,
    NAN,
    NAN,
    NAN,
    NAN,
    NAN,
    NAN,
    NAN,
    NAN,
    False,
    0,
    False,
    False,
)


def setpoint(
    t_us: int, lat: float, lon: float, alt: float, yaw: float, kind: int, acceptance: float, speed: float
) -> Setpoint:
    """One position_setpoint (flat)."""
    return (t_us, lat, lon, NAN, NAN, NAN, alt, yaw, 80.0, acceptance, speed, NAN, True, kind, False, False)


def quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """Hamilton quaternion (w, x, y, z) of ZYX Euler angles, as PX4's vehicle_attitude.q."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def local_position(
    t_us: int,
    pos: tuple[float, float, float],
    vel: tuple[float, float, float],
    acc: tuple[float, float, float],
    heading: float,
    ref: tuple[float, float, float],
    ref_t_us: int,
    valid: bool,
) -> tuple[object, ...]:
    x, y, z = pos
    vx, vy, vz = vel
    dist_bottom = max(-z, 0.0)
    return (
        t_us,
        t_us,
        x,
        y,
        z,
        vx,
        vy,
        vz,
        vz,
        acc[0],
        acc[1],
        acc[2],
        heading,
        0.0,
        dist_bottom,
        0.3,
        0.4,
        0.1,
        0.1,
        ref[0],
        ref[1],
        ref[2],
        ref_t_us,
        NAN,
        NAN,
        NAN,
        NAN,
        valid,
        valid,
        valid,
        valid,
        valid,
        valid,
        True,
        valid,
        False,
    )


def command(
    t_us: int,
    cmd: int,
    params: tuple[float, float, float, float, float, float, float],
    source: tuple[int, int],
    target: tuple[int, int],
    external: bool,
) -> tuple[object, ...]:
    p1, p2, p3, p4, p5, p6, p7 = params
    return (t_us, p5, p6, p1, p2, p3, p4, p7, cmd, target[0], target[1], source[0], source[1], 0, external)
