"""What a test's Collision Prevention set-up will do, said before it flies (``uavtest validate``,
``uavtest run``, the run summary): PX4 v1.15 governs it by its parameters alone, so a test that
asks for ``avoidance: collision-prevention`` without them flies without it, and says so.

PX4 v1.15 runs Collision Prevention only in Position mode, in the flight task of
``MPC_POS_MODE`` 0 (``FlightTaskManualPosition``), when ``CP_DIST`` > 0; never in missions.
"""

from __future__ import annotations

from uavtest.spec.models import Avoidance, Simulator, UavTestSpec

__all__ = ["collision_prevention_warnings"]


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
        if wanted or v.range_sensor is not None or runs:
            out.append(
                "PX4 SITL (SIH, v1.15) has no obstacle-distance sensor (vehicle.avoidance "
                "collision-prevention and vehicle.rangeSensor are built-in simulator only): PX4's "
                "Collision Prevention gets no data"
                + (": position mode will not move and switches to Hold after 5 s" if runs else "")
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
