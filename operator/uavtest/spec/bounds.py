"""The physical range of every number in a test, as shared constrained types.

Every float here refuses NaN and ±infinity (``allow_inf_nan=False``) and has both bounds,
chosen so a PX4 user finds them obviously right: a value outside is a typo or a generator
gone wrong, never a test someone meant to fly. The models (``uavtest.spec.models``) use these
aliases; the loaders of upstream formats (Aerialist YAML, ``.plan``, CSV) check against the
same constants, so one number has one range whichever file it came from.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

__all__ = [
    "ALTITUDE_MAX",
    "ALTITUDE_MIN",
    "DURATION_MAX",
    "LOCAL_MAX",
    "MAX_DEPTH",
    "MAX_FILE_BYTES",
    "MAX_NODES",
    "OBSTACLE_SIZE_MAX",
    "ORBIT_RADIUS_MAX",
    "PARAM_FLOAT_MAX",
    "PARAM_INT_MAX",
    "PARAM_INT_MIN",
    "SPEED_FACTOR_MAX",
    "SPEED_MAX",
    "WIND_MAX",
    "YAW_RATE_MAX",
    "Altitude",
    "AltitudeAmsl",
    "Degrees",
    "Distance",
    "Down",
    "Duration",
    "FaultInstance",
    "Height",
    "Latitude",
    "Local",
    "Longitude",
    "NonNegativeDuration",
    "ObstacleSize",
    "OrbitRadius",
    "ParamFloat",
    "ParamInt",
    "PositiveDistance",
    "Seed",
    "Speed",
    "SpeedFactor",
    "StickAxis",
    "Throttle",
    "Velocity",
    "WindSpeed",
    "YawRate",
]

#: local NED coordinates (x North, y East) and distances: 100 km around home
LOCAL_MAX = 100_000.0
#: heights / altitudes, metres: from the Dead Sea shore to well above any multicopter ceiling
ALTITUDE_MIN = -500.0
ALTITUDE_MAX = 10_000.0
#: an obstacle edge, metres
OBSTACLE_SIZE_MAX = 1_000.0
#: wind speeds, m/s (a strong hurricane; no multicopter flies in it)
WIND_MAX = 50.0
#: ground / climb speeds, m/s
SPEED_MAX = 50.0
#: yaw rates, deg/s (PX4 MPC_YAWRAUTO_MAX / MC_YAWRATE_MAX allow up to 360 deg/s)
YAW_RATE_MAX = 360.0
#: an orbit's radius, metres (PX4 MC_ORBIT_RAD_MAX's largest value, 1 km)
ORBIT_RADIUS_MAX = 1_000.0
#: simulator speed factor (times real time)
SPEED_FACTOR_MAX = 1_000.0
#: durations, times on the vehicle clock, timeouts: one day, seconds
DURATION_MAX = 86_400.0
#: PX4 parameters are INT32 or FLOAT (IEEE single precision)
PARAM_INT_MIN = -(2**31)
PARAM_INT_MAX = 2**31 - 1
PARAM_FLOAT_MAX = 3.4028234663852886e38

#: input documents (YAML, .plan JSON, CSV): largest file, deepest nesting, most values
MAX_FILE_BYTES = 4 * 1024 * 1024
MAX_DEPTH = 64
MAX_NODES = 1_000_000

Latitude = Annotated[float, Field(ge=-90, le=90, allow_inf_nan=False)]
Longitude = Annotated[float, Field(ge=-180, le=180, allow_inf_nan=False)]
#: metres AMSL (home) or above home (mission items)
AltitudeAmsl = Annotated[float, Field(ge=ALTITUDE_MIN, le=ALTITUDE_MAX, allow_inf_nan=False)]
Altitude = AltitudeAmsl
#: NED Down of a point in the air, metres: 0 (home level) up to 10 km (z: -10000)
Down = Annotated[float, Field(ge=-ALTITUDE_MAX, le=0, allow_inf_nan=False)]
#: local NED coordinate, metres from home
Local = Annotated[float, Field(ge=-LOCAL_MAX, le=LOCAL_MAX, allow_inf_nan=False)]
#: a distance or threshold, metres, >= 0
Distance = Annotated[float, Field(ge=0, le=LOCAL_MAX, allow_inf_nan=False)]
PositiveDistance = Annotated[float, Field(gt=0, le=LOCAL_MAX, allow_inf_nan=False)]
#: a height above home, metres, > 0 (takeoff altitude)
Height = Annotated[float, Field(gt=0, le=ALTITUDE_MAX, allow_inf_nan=False)]
#: an angle in degrees (yaw, wind direction): one turn either way
Degrees = Annotated[float, Field(ge=-360, le=360, allow_inf_nan=False)]
ObstacleSize = Annotated[float, Field(gt=0, le=OBSTACLE_SIZE_MAX, allow_inf_nan=False)]
WindSpeed = Annotated[float, Field(ge=0, le=WIND_MAX, allow_inf_nan=False)]
Speed = Annotated[float, Field(gt=0, le=SPEED_MAX, allow_inf_nan=False)]
#: how many times real time a simulator runs (PX4_SIM_SPEED_FACTOR)
SpeedFactor = Annotated[float, Field(gt=0, le=SPEED_FACTOR_MAX, allow_inf_nan=False)]
#: a velocity component (offboard setpoints), m/s, either sign
Velocity = Annotated[float, Field(ge=-SPEED_MAX, le=SPEED_MAX, allow_inf_nan=False)]
#: a yaw rate, deg/s, either sign
YawRate = Annotated[float, Field(ge=-YAW_RATE_MAX, le=YAW_RATE_MAX, allow_inf_nan=False)]
OrbitRadius = Annotated[float, Field(gt=0, le=ORBIT_RADIUS_MAX, allow_inf_nan=False)]
#: MAV_CMD_INJECT_FAILURE param3: 0 = all instances, else the instance (motor 1..N)
FaultInstance = Annotated[int, Field(ge=0, le=255)]
#: a timeout or a flight time, seconds, > 0
Duration = Annotated[float, Field(gt=0, le=DURATION_MAX, allow_inf_nan=False)]
#: a hold time or a time on the vehicle clock, seconds, >= 0
NonNegativeDuration = Annotated[float, Field(ge=0, le=DURATION_MAX, allow_inf_nan=False)]
StickAxis = Annotated[float, Field(ge=-1, le=1, allow_inf_nan=False)]
Throttle = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
Seed = Annotated[int, Field(ge=0, le=2**32 - 1)]
ParamInt = Annotated[int, Field(ge=PARAM_INT_MIN, le=PARAM_INT_MAX)]
ParamFloat = Annotated[float, Field(ge=-PARAM_FLOAT_MAX, le=PARAM_FLOAT_MAX, allow_inf_nan=False)]
