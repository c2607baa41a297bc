"""PX4's navigator (``src/modules/navigator``): mission, hold, takeoff, land and return."""

from __future__ import annotations

from uavtest.sitl.navigator.navigator_main import Event, EventKind, Navigator, State

__all__ = ["Event", "EventKind", "Navigator", "State"]
