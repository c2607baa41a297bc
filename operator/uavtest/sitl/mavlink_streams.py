"""PX4's MAVLink streams (``src/modules/mavlink/streams``): one builder per message.

``STREAMS`` maps a message name to a function of (vehicle, time) that builds it from the
vehicle's current state; ``telemetry.Schedule`` says when each is due.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from uavtest.px4.modes import NavState, base_mode_flags, custom_mode
from uavtest.sitl import mav
from uavtest.sitl.commander.arming import arming_denied
from uavtest.sitl.mav import MavState, Msg
from uavtest.sitl.simulator_sih import GRAVITY
from uavtest.sitl.uorb import quaternion

if TYPE_CHECKING:
    from uavtest.sitl.vehicle import Vehicle

__all__ = ["STREAMS", "SW_VERSION", "autopilot_version", "home_position"]

SW_VERSION = 0x010F0000  # reported as PX4 v1.15.0 compatible


def local_position_ned(v: Vehicle, t: int) -> Msg:
    b, e, st = v.body, v.est, v.st
    return Msg(
        "LOCAL_POSITION_NED",
        {
            "time_boot_ms": t // 1000,
            "x": st.x,
            "y": st.y,
            "z": st.z,
            "vx": b.vx + e.evx,
            "vy": b.vy + e.evy,
            "vz": b.vz + e.evz,
        },
    )


def attitude(v: Vehicle, t: int) -> Msg:
    """streams/ATTITUDE.hpp: vehicle_attitude's Euler angles, vehicle_angular_velocity's body rates."""
    roll, pitch, yaw = _attitude(v)
    p, q, r = v.body.rates()
    return Msg(
        "ATTITUDE",
        {
            "time_boot_ms": t // 1000,
            "roll": roll,
            "pitch": pitch,
            "yaw": yaw,
            "rollspeed": p,
            "pitchspeed": q,
            "yawspeed": r,
        },
    )


def global_position_int(v: Vehicle, t: int) -> Msg:
    b, st = v.body, v.st
    lat, lon = v.proj.reproject(st.x, st.y)
    hdg = round(math.degrees(st.yaw) * 100) % 36000
    return Msg(
        "GLOBAL_POSITION_INT",
        {
            "time_boot_ms": t // 1000,
            "lat": round(lat * 1e7),
            "lon": round(lon * 1e7),
            "alt": round((v.home_alt - st.z) * 1000),
            "relative_alt": round((v.home[2] - st.z) * 1000),
            "vx": round(b.vx * 100),
            "vy": round(b.vy * 100),
            "vz": round(b.vz * 100),
            "hdg": hdg,
        },
    )


def heartbeat(v: Vehicle, t: int) -> Msg:
    if v.crashed:
        state = MavState.EMERGENCY
    elif v.failsafe:
        state = MavState.CRITICAL
    elif v.armed:
        state = MavState.ACTIVE
    else:
        state = MavState.STANDBY if v.ready else MavState.BOOT
    return Msg(
        "HEARTBEAT",
        {
            "type": mav.MAV_TYPE_QUADROTOR,
            "autopilot": mav.MAV_AUTOPILOT_PX4,
            "base_mode": base_mode_flags(v.nav_state, v.armed),
            "custom_mode": custom_mode(v.nav_state),
            "system_status": int(state),
            "mavlink_version": 3,
        },
    )


def extended_sys_state(v: Vehicle, t: int) -> Msg:
    return Msg("EXTENDED_SYS_STATE", {"vtol_state": 0, "landed_state": int(v.landed_state())})


def sys_status(v: Vehicle, t: int) -> Msg:
    health = mav.SYS_STATUS_SENSORS & ~mav.SYS_STATUS_GPS
    if v.ready:
        health |= mav.SYS_STATUS_GPS
        # vehicle_status.pre_flight_checks_pass: canArm in the current mode (disarmed in Position
        # mode without sticks, Return, Mission without a mission, ...: clear, as on PX4 v1.15)
        if not v.crashed and (v.armed or arming_denied(v) is None):
            health |= mav.SYS_STATUS_PREARM_CHECK
    return Msg(
        "SYS_STATUS",
        {
            "onboard_control_sensors_present": mav.SYS_STATUS_SENSORS | mav.SYS_STATUS_PREARM_CHECK,
            "onboard_control_sensors_enabled": mav.SYS_STATUS_SENSORS | mav.SYS_STATUS_PREARM_CHECK,
            "onboard_control_sensors_health": health,
            "load": 100,
            **_sys_status_battery(v),
            "drop_rate_comm": 0,
            "errors_comm": 0,
            "errors_count1": 0,
            "errors_count2": 0,
            "errors_count3": 0,
            "errors_count4": 0,
        },
    )


def system_time(v: Vehicle, t: int) -> Msg:
    """Host clock at boot + vehicle time (``SimConfig.utc_boot_us``; 0 in-process: 1970)."""
    utc = v.config.utc_boot_us
    return Msg("SYSTEM_TIME", {"time_unix_usec": utc + t if utc else 0, "time_boot_ms": t // 1000})


# ---------------------------------------------------------------- attitude, odometry, sensors

#: Earth magnetic field (gauss, NED) the simulated magnetometer reads (mid-latitude Europe)
MAG_NED = (0.21, 0.01, 0.43)
BARO_TEMPERATURE_C = 20.0  # constant: the simulator models no temperature
_ISA_P0 = 101325.0  # Pa


def _attitude(v: Vehicle) -> tuple[float, float, float]:
    """vehicle_attitude: EKF2's roll, pitch (off the truth by its tilt error) and heading."""
    roll, pitch = v.estimated_tilt(*v.body.tilt())
    return roll, pitch, v.st.yaw


def _to_body(
    roll: float, pitch: float, yaw: float, n: float, e: float, d: float
) -> tuple[float, float, float]:
    """A NED vector in the body frame (FRD) of ZYX Euler angles: R(yaw, pitch, roll)^T v."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    x1 = cy * n + sy * e  # undo yaw
    y1 = -sy * n + cy * e
    x2 = cp * x1 - sp * d  # undo pitch
    z2 = sp * x1 + cp * d
    return x2, cr * y1 + sr * z2, -sr * y1 + cr * z2  # undo roll


def isa_pressure_hpa(alt_amsl: float) -> float:
    """ISA static pressure (hPa) at an altitude above mean sea level (troposphere)."""
    return _ISA_P0 * (1.0 - 2.25577e-5 * alt_amsl) ** 5.25588 / 100.0


def attitude_quaternion(v: Vehicle, t: int) -> Msg:
    """streams/ATTITUDE_QUATERNION.hpp: vehicle_attitude.q (w, x, y, z), body rates."""
    q = quaternion(*_attitude(v))
    p, q_rate, r = v.body.rates()
    return Msg(
        "ATTITUDE_QUATERNION",
        {
            "time_boot_ms": t // 1000,
            "q1": q[0],
            "q2": q[1],
            "q3": q[2],
            "q4": q[3],
            "rollspeed": p,
            "pitchspeed": q_rate,
            "yawspeed": r,
            "repr_offset_q": [0.0, 0.0, 0.0, 0.0],
        },
    )


def odometry(v: Vehicle, t: int) -> Msg:
    """streams/ODOMETRY.hpp from ekf2's vehicle_odometry: pose in LOCAL_NED, velocity in NED
    (ekf2 publishes VELOCITY_FRAME_NED), variances on the diagonals, the rest NaN."""
    b, e, st = v.body, v.est, v.st
    pose_cov = [math.nan] * 21
    vel_cov = [math.nan] * 21
    pose_cov[0] = pose_cov[6] = 0.12**2  # ekf2.SIGMA_XY
    pose_cov[11] = 0.08**2  # ekf2.SIGMA_Z
    pose_cov[15] = pose_cov[18] = pose_cov[20] = 0.005**2
    vel_cov[0] = vel_cov[6] = vel_cov[11] = 0.03**2
    p, q, r = b.rates()  # vehicle_odometry.angular_velocity: body rates
    return Msg(
        "ODOMETRY",
        {
            "time_usec": t,
            "frame_id": 1,  # MAV_FRAME_LOCAL_NED
            "child_frame_id": 1,  # MAV_FRAME_LOCAL_NED: velocity in NED
            "x": st.x,
            "y": st.y,
            "z": st.z,
            "q": list(quaternion(*_attitude(v))),
            "vx": b.vx + e.evx,
            "vy": b.vy + e.evy,
            "vz": b.vz + e.evz,
            "rollspeed": p,
            "pitchspeed": q,
            "yawspeed": r,
            "pose_covariance": pose_cov,
            "velocity_covariance": vel_cov,
            "reset_counter": 0,
            "estimator_type": 8,  # MAV_ESTIMATOR_TYPE_AUTOPILOT
            "quality": 0,
        },
    )


def altitude(v: Vehicle, t: int) -> Msg:
    """streams/ALTITUDE.hpp: baro (monotonic), AMSL, local -z, relative to home; no terrain."""
    st = v.st
    amsl = v.home_alt - st.z
    return Msg(
        "ALTITUDE",
        {
            "time_usec": t,
            "altitude_monotonic": v.home_alt - v.body.z,
            "altitude_amsl": amsl,
            "altitude_local": -st.z,
            "altitude_relative": -(st.z - v.home[2]),
            "altitude_terrain": math.nan,
            "bottom_clearance": math.nan,
        },
    )


def highres_imu(v: Vehicle, t: int) -> Msg:
    """streams/HIGHRES_IMU.hpp from the true body: specific force (thrust + drag, minus gravity;
    -g on the ground) and the magnetic field rotated into the body frame, body rates, baro from
    the ISA at the true altitude, constant temperature."""
    b = v.body
    roll, pitch = b.tilt()  # the IMU turns with the true body
    yaw = v.st.yaw
    if b.on_ground:
        fn, fe, fd = 0.0, 0.0, -GRAVITY
    else:  # the last physics step's kinematic acceleration, less gravity
        fn, fe, fd = b.kax, b.kay, b.kaz - GRAVITY
    ax, ay, az = _to_body(roll, pitch, yaw, fn, fe, fd)
    mx, my, mz = _to_body(roll, pitch, yaw, *MAG_NED)
    gx, gy, gz = b.rates()
    alt = v.home_alt - b.z
    return Msg(
        "HIGHRES_IMU",
        {
            "time_usec": t,
            "xacc": ax,
            "yacc": ay,
            "zacc": az,
            "xgyro": gx,
            "ygyro": gy,
            "zgyro": gz,
            "xmag": mx,
            "ymag": my,
            "zmag": mz,
            "abs_pressure": isa_pressure_hpa(alt),
            "diff_pressure": 0.0,
            "pressure_alt": alt,
            "temperature": BARO_TEMPERATURE_C,
            "fields_updated": 0x1FFF,
            "id": 0,
        },
    )


def scaled_pressure(v: Vehicle, t: int) -> Msg:
    """streams/SCALED_PRESSURE.hpp: the baro's pressure (ISA at the true altitude), cdegC."""
    return Msg(
        "SCALED_PRESSURE",
        {
            "time_boot_ms": t // 1000,
            "press_abs": isa_pressure_hpa(v.home_alt - v.body.z),
            "press_diff": 0.0,
            "temperature": round(BARO_TEMPERATURE_C * 100),
            "temperature_press_diff": 0,
        },
    )


def wind_cov(v: Vehicle, t: int) -> Msg:
    """streams/WIND_COV.hpp: the wind (north, east; z 0 as PX4), variance of the gust model,
    at the vehicle's AMSL altitude."""
    w = v.wind
    return Msg(
        "WIND_COV",
        {
            "time_usec": t,
            "wind_x": w.n,
            "wind_y": w.e,
            "wind_z": 0.0,
            "var_horiz": 2.0 * w.sigma * w.sigma,
            "var_vert": 0.0,
            "wind_alt": v.home_alt - v.st.z,
            "horiz_accuracy": 0.0,
            "vert_accuracy": 0.0,
        },
    )


def home_position(v: Vehicle, t: int) -> Msg:
    hx, hy, hz, lat, lon, alt, _ = v.home
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


def mission_current(v: Vehicle, t: int) -> Msg:
    nav = v.nav
    total = len(nav.mission)
    in_mission = v.nav_state == NavState.AUTO_MISSION
    state = 1 if total == 0 else 5 if nav.finished else 3 if in_mission else 2
    return Msg(
        "MISSION_CURRENT",
        {
            "seq": min(nav.current, 65535),
            "total": total,
            "mission_state": state,
            "mission_mode": int(in_mission),
        },
    )


def vfr_hud(v: Vehicle, t: int) -> Msg:
    b, st = v.body, v.st
    return Msg(
        "VFR_HUD",
        {
            "airspeed": math.hypot(b.vx - v.wind.n, b.vy - v.wind.e),
            "groundspeed": math.hypot(b.vx, b.vy),
            "heading": round(math.degrees(st.yaw)) % 360,
            "throttle": 50 if b.motors else 0,
            "alt": v.home_alt - st.z,
            "climb": -b.vz,
        },
    )


def _sys_status_battery(v: Vehicle) -> dict[str, int]:
    """SYS_STATUS battery fields from battery_status (streams/SYS_STATUS.hpp)."""
    b = v.battery.status
    if b is None or not b.connected:
        return {"voltage_battery": 65535, "current_battery": -1, "battery_remaining": -1}
    return {
        "voltage_battery": round(b.voltage_filtered_v * 1000.0),
        "current_battery": round(b.current_filtered_a * 100.0),
        "battery_remaining": math.ceil(b.remaining * 100.0),
    }


#: battery_status.warning → MAV_BATTERY_CHARGE_STATE (OK, LOW, CRITICAL, EMERGENCY)
_CHARGE_STATE = (1, 2, 3, 4)


def battery_status(v: Vehicle, t: int) -> Msg:
    """BATTERY_STATUS from battery_status (streams/BATTERY_STATUS.hpp): the total voltage in the
    first cell slot (no per-cell voltages), current -1 A (battery_simulator has no sensor)."""
    b = v.battery.status
    connected = b is not None and b.connected
    voltages = [65535] * 10
    if connected:
        voltages[0] = round(b.voltage_filtered_v * 1000.0)  # type: ignore[union-attr]
    return Msg(
        "BATTERY_STATUS",
        {
            "id": 0,
            "battery_function": 1,
            "type": 1,
            "temperature": 32767,
            "voltages": voltages,
            "current_battery": round(b.current_filtered_a * 100.0) if connected else -1,  # type: ignore[union-attr]
            "current_consumed": round(b.discharged_mah) if connected else -1,  # type: ignore[union-attr]
            "energy_consumed": -1,
            "battery_remaining": round(b.remaining * 100.0) if connected else -1,  # type: ignore[union-attr]
            "time_remaining": 0,
            "charge_state": _CHARGE_STATE[b.warning] if connected and b.warning < 4 else 0,  # type: ignore[union-attr]
            "voltages_ext": [0, 0, 0, 0],
            "mode": 0,
            "fault_bitmask": b.faults if connected else 0,  # type: ignore[union-attr]
        },
    )


def gps_raw_int(v: Vehicle, t: int) -> Msg:
    b = v.body
    lat, lon = v.proj.reproject(b.x, b.y)
    return Msg(
        "GPS_RAW_INT",
        {
            "time_usec": t,
            "fix_type": 3 if v.ready and not v.gps.blocked else 0,
            "lat": round(lat * 1e7),
            "lon": round(lon * 1e7),
            "alt": round((v.home_alt - b.z) * 1000),
            "eph": 70,
            "epv": 100,
            "vel": round(math.hypot(b.vx, b.vy) * 100),
            "cog": 0,
            "satellites_visible": 12,
        },
    )


def autopilot_version(v: Vehicle) -> Msg:
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
            "uid": 1 + v.config.seed,
            "uid2": [0] * 18,
        },
    )


def orbit_execution_status(v: Vehicle, t: int) -> Msg:
    """ORBIT_EXECUTION_STATUS from the Orbit task's orbit_status (streams/ORBIT_EXECUTION_STATUS.hpp):
    radius signed by direction, frame MAV_FRAME_GLOBAL, centre lat/lon 1e7, altitude AMSL. Sent
    only in nav state ORBIT (PX4 publishes orbit_status only while the task runs), at
    ``ORBIT_STATUS_HZ``."""
    o = v.nav.orbit.status()
    lat, lon = v.proj.reproject(o.x, o.y)
    return Msg(
        "ORBIT_EXECUTION_STATUS",
        {
            "time_usec": t,
            "radius": o.radius,
            "frame": 0,
            "x": round(lat * 1e7),
            "y": round(lon * 1e7),
            "z": v.home_alt - o.z,
        },
    )


#: ORBIT_EXECUTION_STATUS rate: mavlink_main.cpp "normal" mode (the GCS link) configures 2 Hz
ORBIT_STATUS_HZ = 2.0

#: message name → builder
#: OBSTACLE_DISTANCE goes out only for an obstacle_distance_fused published this recently
FUSED_FRESH_US = 100_000


def obstacle_distance(v: Vehicle, t: int) -> Msg | None:
    """streams/OBSTACLE_DISTANCE.hpp: Collision Prevention's map (``obstacle_distance_fused``),
    sent only when CP has published it (it runs in position mode with CP_DIST > 0 and
    MPC_POS_MODE 0); ``increment`` 0, the increment in ``increment_f``. None: nothing to send."""
    cp = v.ctrl.velocity_constraint
    fused = getattr(cp, "published", None)
    if fused is None or t - cp.last_call_us > FUSED_FRESH_US:  # type: ignore[union-attr]
        return None
    return Msg(
        "OBSTACLE_DISTANCE",
        {
            "time_usec": fused.timestamp,
            "sensor_type": fused.sensor_type,
            "distances": list(fused.distances),
            "increment": 0,
            "min_distance": fused.min_distance,
            "max_distance": fused.max_distance,
            "increment_f": fused.increment,
            "angle_offset": fused.angle_offset,
            "frame": fused.frame,
        },
    )


def distance_sensor(v: Vehicle, t: int) -> Msg | None:
    """streams/DISTANCE_SENSOR.hpp: the range sensor's distance_sensor (forward reading), cm;
    None without a sensor."""
    rs = v.sim.range_sensor
    ds = rs.last_range if rs is not None else None
    if ds is None:
        return None
    return Msg(
        "DISTANCE_SENSOR",
        {
            "time_boot_ms": ds.timestamp // 1000,
            "min_distance": int(ds.min_distance * 1e2),
            "max_distance": int(ds.max_distance * 1e2),
            "current_distance": min(int(ds.current_distance * 1e2), 65535),
            "type": ds.type,
            "id": 0,
            "orientation": ds.orientation,
            "covariance": int(ds.variance * 1e4),
        },
    )


STREAMS: dict[str, Callable[[Vehicle, int], Msg | None]] = {
    "LOCAL_POSITION_NED": local_position_ned,
    "ATTITUDE": attitude,
    "GLOBAL_POSITION_INT": global_position_int,
    "HEARTBEAT": heartbeat,
    "EXTENDED_SYS_STATE": extended_sys_state,
    "SYS_STATUS": sys_status,
    "SYSTEM_TIME": system_time,
    "HOME_POSITION": home_position,
    "MISSION_CURRENT": mission_current,
    "VFR_HUD": vfr_hud,
    "BATTERY_STATUS": battery_status,
    "GPS_RAW_INT": gps_raw_int,
    "ATTITUDE_QUATERNION": attitude_quaternion,
    "ODOMETRY": odometry,
    "ALTITUDE": altitude,
    "HIGHRES_IMU": highres_imu,
    "SCALED_PRESSURE": scaled_pressure,
    "WIND_COV": wind_cov,
    "OBSTACLE_DISTANCE": obstacle_distance,
    "DISTANCE_SENSOR": distance_sensor,
}
