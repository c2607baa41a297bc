"""How a flight passes its waypoints: how close its first pass comes, and how long until accepted.

PX4's navigator accepts a multicopter waypoint once the vehicle is within the acceptance radius
(``NAV_ACC_RAD``, or the item's own) horizontally (``MissionBlock::is_mission_item_reached``). A
vehicle that brakes onto the waypoint but passes it just outside that radius is not accepted: it
turns to face the waypoint (``MPC_YAW_MODE`` 0 points at the target from outside the radius) and
creeps back onto it, seconds later. With the competition's 0.5 m that is a knife edge: in 12
PX4 v1.15 SIH flights of mission2 the first pass at its far waypoint came within 0.46-0.54 m, and
the three shared logs that missed by 2-4 cm took 6 s longer there.

``first_passes`` measures that from a flight's logged position and its setpoint triplet's
changes, per leg (a target set at least ``LEG_MIN`` metres from the vehicle):

- ``closest``: the least horizontal distance to the target on the first pass, which starts when
  the vehicle first comes within ``APPROACH`` metres (before the target changes) and ends when
  it has moved ``RETREAT`` metres further out than that least distance (or the log ends): past
  its acceptance, as the vehicle may still be closing in;
- ``accepted_after``: from the start of that pass to the triplet's next change (the navigator
  moving on: the next waypoint, or a landing item's descent), in seconds; NaN when the log ends
  first;
- ``acceptance_radius``: the radius the triplet gave for that target.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["APPROACH", "LEG_MIN", "RETREAT", "WaypointPass", "first_passes"]

LEG_MIN = 5.0  # m: a target set this far from the vehicle is a leg to pass, not a hover
APPROACH = 2.0  # m: the first pass starts this close to the target
RETREAT = 0.3  # m: and ends this much further out than the closest it came


@dataclass(frozen=True, slots=True)
class WaypointPass:
    """One leg's arrival (module docstring)."""

    closest: float
    accepted_after: float
    acceptance_radius: float

    @property
    def missed(self) -> bool:
        """The first pass stayed outside the acceptance radius."""
        return self.closest > self.acceptance_radius


def first_passes(t: np.ndarray, x: np.ndarray, y: np.ndarray, changes: np.ndarray) -> list[WaypointPass]:
    """Every leg's first pass, in time order.

    ``t`` (s), ``x``, ``y`` (m): the logged horizontal position. ``changes``: one row per change
    of the triplet's current setpoint (its position or its type), ``(time, x, y, acceptance
    radius)`` in the same frame, in time order. A leg the vehicle never came within
    ``APPROACH`` of is left out.
    """
    out: list[WaypointPass] = []
    for k, (start, tx, ty, radius) in enumerate(changes):
        end = changes[k + 1][0] if k + 1 < len(changes) else np.inf
        i = int(np.searchsorted(t, start))
        if i >= len(t) or np.hypot(x[i] - tx, y[i] - ty) < LEG_MIN:
            continue
        d = np.hypot(x[i:] - tx, y[i:] - ty)
        near = np.flatnonzero(d < APPROACH)
        if not len(near) or t[i + near[0]] >= end:
            continue
        # the pass runs on past its acceptance: the vehicle may still be closing in
        passing = d[near[0] :]
        low = np.minimum.accumulate(passing)
        out_again = np.flatnonzero(passing > low + RETREAT)
        closest = float(low[out_again[0]] if len(out_again) else low[-1])
        arrived = float(t[i + near[0]])
        accepted = end - arrived if np.isfinite(end) else float("nan")
        out.append(WaypointPass(closest, float(accepted), float(radius)))
    return out
