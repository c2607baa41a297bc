"""Return mode's arithmetic, as PX4 v1.15's navigator does it for a multicopter.

Follows ``src/modules/navigator/rtl.cpp`` and ``rtl_direct.cpp`` (release/1.15, RTL_TYPE 0, no
VTOL land approaches, WV_EN 0):

- the return altitude (``RTL::findRtlDestination``): with ``RTL_CONE_ANG`` 0, the higher of the
  current altitude and ``RTL_RETURN_ALT`` above the destination, whatever the distance; with a
  cone (PX4's default 45), ``RTL::calculate_return_alt_from_cone_half_angle`` lowers it near the
  destination: within ``RTL_MIN_DIST``, ``dist / tan(angle)`` above the destination (the angle
  clamped to 1-89 degrees) but at least ``2 NAV_ACC_RAD``, within ``NAV_ACC_RAD`` ``2 dist``;
  never below the current altitude;
- the activation's text (``RtlDirect::on_activation``), from the float32 AMSL altitudes PX4
  keeps (``home_position.alt``, ``vehicle_global_position.alt``) rounded up with ``ceilf``;
- an RTL item's heading (``MissionBlock::is_mission_item_reached_or_completed``, a multicopter,
  ``force_heading`` false without land approaches): accepted within ``MIS_YAW_ERR``, or at once
  when ``MIS_YAW_TMT`` is set, or when there is none to wait for.
"""

from __future__ import annotations

import math
import struct

from uavtest.sitl.mc_pos_control import wrap_pi

__all__ = [
    "FLT_EPSILON",
    "f32",
    "rtl_heading_accepted",
    "rtl_loiters_forever",
    "rtl_return_altitude",
    "rtl_start_text",
]

FLT_EPSILON = 1.1920929e-07


def f32(value: float) -> float:
    """``value`` rounded to single precision, as PX4 holds altitudes (``float``)."""
    return struct.unpack("<f", struct.pack("<f", value))[0]


def rtl_return_altitude(
    dist: float,
    dest_alt: float,
    alt: float,
    *,
    return_alt: float,
    cone_half_angle_deg: int,
    min_dist: float,
    acc_rad: float,
) -> float:
    """The altitude a multicopter returns at (same datum as ``dest_alt`` and ``alt``): rtl.cpp
    ``RTL::findRtlDestination`` (~lines 473-479) and
    ``RTL::calculate_return_alt_from_cone_half_angle`` (~519-553). ``dist`` is the horizontal
    distance to the destination, ``alt`` the vehicle's altitude."""
    if cone_half_angle_deg <= 0:
        return max(alt, dest_alt + return_alt)
    ret = dest_alt + return_alt
    if dist <= acc_rad:
        ret = dest_alt + 2.0 * dist
    else:
        if dist <= min_dist:
            half_angle = math.radians(min(max(cone_half_angle_deg, 1.0), 89.0))
            ret = min(dist / math.tan(half_angle) + dest_alt, ret)
        # outside the acceptance radius at least twice it: no touching the ground on the way
        ret = max(ret, dest_alt + 2.0 * acc_rad)
    return max(ret, alt)


def rtl_start_text(rtl_alt_amsl: float, dest_alt_amsl: float) -> str:
    """``RtlDirect::on_activation``'s mavlink_log_info (rtl_direct.cpp ~line 89): both figures
    ``(int)ceilf`` of float32 metres, the first AMSL."""
    rtl, dest = f32(rtl_alt_amsl), f32(dest_alt_amsl)
    above = f32(rtl - dest)
    return f"RTL: start return at {math.ceil(rtl)} m ({math.ceil(above)} m above destination)"


def rtl_loiters_forever(land_delay: float) -> bool:
    """``RTL_LAND_DELAY`` negative: ``setLoiterHoldMissionItem`` makes the hold a LOITER_UNLIMITED
    (never reached, no landing) and ``RtlDirect::set_rtl_item`` says "RTL: completed, loitering"."""
    return land_delay < -FLT_EPSILON


def rtl_heading_accepted(
    yaw_sp: float,
    heading: float,
    yaw_err_deg: float,
    yaw_timeout: float,
    yaw_acceptance: bool = True,
    *,
    forced: bool = False,
) -> bool:
    """``MissionBlock::is_mission_item_reached_or_completed``'s heading for a multicopter, an RTL
    item's (never ``force_heading`` without land approaches) as a mission item's: none to wait
    for (NaN, or obstacle avoidance's NaN yaw_acceptance: ``Navigator::get_yaw_to_be_accepted``),
    within ``MIS_YAW_ERR``, or ``MIS_YAW_TMT`` set, which accepts an unforced heading at once."""
    if not yaw_acceptance or not math.isfinite(yaw_sp):
        return True
    within = abs(wrap_pi(yaw_sp - heading)) < math.radians(yaw_err_deg)
    return within or (yaw_timeout >= FLT_EPSILON and not forced)
