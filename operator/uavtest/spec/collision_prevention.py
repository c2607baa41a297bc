"""What a test's Collision Prevention set-up will do, said before it flies (``uavtest validate``,
``uavtest run``, the run summary): PX4 v1.15 governs it by its parameters alone, so a test that
asks for ``avoidance: collision-prevention`` without them flies without it, and says so.

PX4 v1.15 runs Collision Prevention only in Position mode, in the flight task of
``MPC_POS_MODE`` 0 (``FlightTaskManualPosition``), when ``CP_DIST`` > 0; never in missions.
"""

from __future__ import annotations

from uavtest.spec.models import Avoidance, RangeSensor, Simulator, UavTestSpec

__all__ = ["collision_prevention_warnings", "range_sensor_of"]


def range_sensor_of(spec: UavTestSpec) -> RangeSensor | None:
    """The test's range sensor: ``vehicle.rangeSensor``, or its defaults with collision-prevention.
    The built-in vehicle carries it; for PX4 SITL the runner simulates it
    (``uavtest.runner.obstacle_distance``)."""
    v = spec.vehicle
    if v.range_sensor is None and v.avoidance is Avoidance.COLLISION_PREVENTION:
        return RangeSensor()
    return v.range_sensor


def _param(spec: UavTestSpec, name: str) -> float:
    from uavtest.sitl.params import DEFAULTS

    value = spec.vehicle.params.get(name)
    return float(DEFAULTS[name][1] if value is None else value)


def collision_prevention_warnings(spec: UavTestSpec) -> list[str]:
    """Warnings for a Collision Prevention set-up that will not act as the test seems to expect."""
    v = spec.vehicle
    cp_dist, pos_mode = _param(spec, "CP_DIST"), int(_param(spec, "MPC_POS_MODE"))
    wanted = v.avoidance is Avoidance.COLLISION_PREVENTION
    out: list[str] = []
    runs = cp_dist > 0 and pos_mode == 0
    if v.simulator is Simulator.PX4:
        sensor = range_sensor_of(spec)
        if sensor is not None:
            out.append(
                "PX4 SITL (SIH, v1.15) has no obstacle-distance sensor: the runner sends PX4 "
                f"OBSTACLE_DISTANCE as a companion computer would, scanned from the test's boxes at "
                f"{sensor.rate:g} Hz of vehicle time where PX4's estimate puts the vehicle (PX4 drops "
                "scans older than 0.5 s of its clock: at a high speed factor on a busy machine, "
                "give a lower vehicle.speedFactor)"
            )
        elif runs:
            out.append(
                f"CP_DIST is {cp_dist:g} but the vehicle has no range sensor (PX4 SITL's SIH has none; "
                "vehicle.avoidance collision-prevention or vehicle.rangeSensor makes the runner send "
                "one's scans): PX4's Collision Prevention gets no data, position mode will not move "
                "and switches to Hold after 5 s"
            )
        return out
    if wanted and cp_dist <= 0:
        out.append(
            f"vehicle.avoidance is collision-prevention but CP_DIST is {cp_dist:g} (PX4's default "
            "-1 turns it off): Collision Prevention is off, the range sensor only reports; set "
            "vehicle.params.CP_DIST to the distance to keep (metres, > 0)"
        )
    if cp_dist > 0 and pos_mode != 0:
        out.append(
            f"CP_DIST is {cp_dist:g} but MPC_POS_MODE is {pos_mode}: PX4 v1.15 runs Collision "
            "Prevention only in the position-mode task of MPC_POS_MODE 0 (direct velocity), so "
            "it is off; set vehicle.params.MPC_POS_MODE: 0"
        )
    if cp_dist > 0 and pos_mode == 0 and v.range_sensor is None and not wanted:
        out.append(
            f"CP_DIST is {cp_dist:g} but the vehicle has no range sensor (vehicle.avoidance "
            f"{v.avoidance.value}, no vehicle.rangeSensor): as PX4 without obstacle data, "
            "position mode will not move and switches to Hold after 5 s"
        )
    m = spec.mission
    if wanted and m is not None and (m.waypoints or m.plan or m.plan_file):
        out.append(
            "Collision Prevention acts only in position mode (PX4 v1.15): the mission and the "
            "other auto modes fly without it"
        )
    return out
