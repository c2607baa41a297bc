"""PX4's commander (``src/modules/commander``): arming, modes, failsafes and vehicle commands.

- ``commander``: the state machine (readiness, arming, nav state, auto-disarm, failsafes);
- ``arming``: the pre-arm checks and arming/disarming reasons, as a table;
- ``failsafe``: failsafe conditions and the nav state each configured action switches to;
- ``vehicle_command``: COMMAND_LONG / COMMAND_INT dispatch, one handler per command.
"""

from __future__ import annotations

__all__: list[str] = []
