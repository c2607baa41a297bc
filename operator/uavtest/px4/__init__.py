"""PX4's own numbers, in one place for the runner and the built-in simulator alike."""

from __future__ import annotations

__all__: list[str] = []
