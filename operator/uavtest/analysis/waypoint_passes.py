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

``corner_exits`` measures what follows, per waypoint a new leg starts from (the next target at
least ``LEG_MIN`` metres on): how far off that new leg the vehicle gets within ``EXIT_WINDOW``
seconds of the acceptance (beyond the acceptance radius FlightTaskAuto goes "offtrack" and heads
back to the track at walking pace first), and how long until it is ``EXIT_DOWN`` metres down the
new leg. PX4 v1.15 SIH at mission2's far waypoint: 6 of 8 flights more than 0.5 m off, 5.7 s
(median) to be 5 m down the way back.

``midleg_brakes`` counts what the same state does in the middle of a leg. Once the estimate is
farther than the acceptance radius from the line between the waypoints, FlightTaskAuto aims at
the closest point on the track with the real target next, a near right-angle corner a few
decimetres away, and its trajectory brakes nearly to a stop before it goes on. Per leg of at least
``MIDLEG_LEG`` metres: every time the trajectory setpoint's speed along the leg falls below
``MIDLEG_SLOW`` from ``MIDLEG_AFTER`` seconds after the leg started until ``MIDLEG_BEFORE``
metres before its end (its own braking into the waypoint), and how far before the end. 24 PX4
v1.15 SIH flights of the competition's missions (2026-11-27): in 16 of 40 legs, 14 of them 10-27 m
before the end; ``after``, how long after the leg started: median 10.6 s there (20 brakes), the
built-in vehicle 8.0 s, 20 of its 53 brakes within 6 s (stop 38: it goes offtrack as its
acceleration out of the corner ends, PX4 late in the leg).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "APPROACH",
    "EXIT_DOWN",
    "EXIT_WINDOW",
    "LEG_MIN",
    "MIDLEG_AFTER",
    "MIDLEG_BEFORE",
    "MIDLEG_LEG",
    "MIDLEG_MERGE",
    "MIDLEG_SLOW",
    "RETREAT",
    "CornerExit",
    "MidLegBrakes",
    "WaypointPass",
    "corner_exits",
    "first_passes",
    "midleg_brakes",
]

LEG_MIN = 5.0  # m: a target set this far from the vehicle is a leg to pass, not a hover
APPROACH = 2.0  # m: the first pass starts this close to the target
RETREAT = 0.3  # m: and ends this much further out than the closest it came
EXIT_WINDOW = 2.0  # s after the acceptance: how far off the new leg the vehicle gets
EXIT_DOWN = 5.0  # m down the new leg: how long until the vehicle is on its way
MIDLEG_LEG = 40.0  # m: legs at least this long are looked at for braking mid-leg
MIDLEG_AFTER = 5.0  # s after the leg starts: its acceleration out of the waypoint is over
MIDLEG_BEFORE = 10.0  # m before the leg's end: its braking into the waypoint has not begun
MIDLEG_SLOW = 2.5  # m/s: the trajectory setpoint's speed along the leg below which it braked
MIDLEG_MERGE = 1.0  # s: slow stretches closer together than this are one brake


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


@dataclass(frozen=True, slots=True)
class CornerExit:
    """One waypoint left for a new leg (module docstring)."""

    off_leg: float  # m: the farthest off the new leg within EXIT_WINDOW s of the acceptance
    seconds_down: float  # s from the acceptance to EXIT_DOWN m down the new leg; NaN: never
    acceptance_radius: float

    @property
    def offtrack(self) -> bool:
        """It got farther off the new leg than the acceptance radius (FlightTaskAuto offtrack)."""
        return self.off_leg > self.acceptance_radius


def corner_exits(t: np.ndarray, x: np.ndarray, y: np.ndarray, changes: np.ndarray) -> list[CornerExit]:
    """Every waypoint a new leg starts from, in time order (module docstring); ``t``, ``x``, ``y``
    and ``changes`` as for ``first_passes``. A waypoint the vehicle was never near (within
    ``APPROACH``) at its acceptance, or a next target closer than ``LEG_MIN``, is left out."""
    out: list[CornerExit] = []
    for k in range(len(changes) - 1):
        _, wx, wy, radius = changes[k]
        accepted, nx, ny, _ = changes[k + 1]
        leg = np.array([nx - wx, ny - wy])
        length = float(np.hypot(*leg))
        i = int(np.searchsorted(t, accepted))
        if length < LEG_MIN or i >= len(t) or np.hypot(x[i] - wx, y[i] - wy) > APPROACH:
            continue
        along = leg / length
        rel = np.column_stack([x[i:] - wx, y[i:] - wy])
        soon = t[i:] <= accepted + EXIT_WINDOW
        off = float(np.abs(rel[soon] @ np.array([-along[1], along[0]])).max())
        down = np.flatnonzero(rel @ along >= EXIT_DOWN)
        seconds = float(t[i + down[0]] - accepted) if len(down) else float("nan")
        out.append(CornerExit(off, seconds, float(radius)))
    return out


@dataclass(frozen=True, slots=True)
class MidLegBrakes:
    """How often a flight's trajectory braked mid-leg (module docstring)."""

    legs: int  # legs of at least MIDLEG_LEG metres the flight started
    to_go: tuple[float, ...]  # m before its leg's end, per brake
    after: tuple[float, ...] = ()  # s after its leg started, per brake


def midleg_brakes(
    t: np.ndarray, x: np.ndarray, y: np.ndarray, vx: np.ndarray, vy: np.ndarray, changes: np.ndarray
) -> MidLegBrakes:
    """The trajectory's brakes mid-leg (module docstring). ``t`` (s), ``x``, ``y`` (m), ``vx``,
    ``vy`` (m/s): the trajectory setpoint (``trajectory_setpoint``); ``changes`` as for
    ``first_passes``: a leg runs from one target to the next, from the change that set it to the
    next change."""
    legs = 0
    to_go: list[float] = []
    after: list[float] = []
    for k in range(1, len(changes)):
        _, px, py, _ = changes[k - 1]
        start, tx, ty, _ = changes[k]
        end = changes[k + 1][0] if k + 1 < len(changes) else np.inf
        leg = np.array([tx - px, ty - py])
        length = float(np.hypot(*leg))
        if length < MIDLEG_LEG:
            continue
        legs += 1
        along = leg / length
        m = (t >= start + MIDLEG_AFTER) & (t < end)
        remaining = (tx - x[m]) * along[0] + (ty - y[m]) * along[1]
        slow = (vx[m] * along[0] + vy[m] * along[1] < MIDLEG_SLOW) & (remaining > MIDLEG_BEFORE)
        times = t[m]
        last = -np.inf  # when the last brake's slow stretch ended
        for i in np.flatnonzero(slow):
            if times[i] - last > MIDLEG_MERGE:  # a new brake, not the same one dithering
                to_go.append(float(remaining[i]))
                after.append(float(times[i] - start))
            last = times[i]
    return MidLegBrakes(legs, tuple(to_go), tuple(after))
