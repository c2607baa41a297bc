"""What the fork server does once, before forking, so that no replica process does it again.

``launch.PRELOAD`` imports this module in the warm fork server. Measured in forked replica
processes of the built-in simulator (2-core machine, mission2, 20 replicas: about 60 ms of CPU
in each of a replica's two processes, 8 % of a flight's CPU), each one was still:

- building the replica command line from its functions' signatures (typer, ~18 ms);
- importing the test file loaders (``uavtest.spec.loaders`` and what it imports: compiled from
  source in every process when Python writes no bytecode, ~23 ms);
- reading PX4's parameter metadata (``parameters_v1_15.json``, ~20 ms), which every test's
  parameters are checked against.

Importing this module does all three; a forked process finds them done (cached), and a process
started on its own does them as before, on first use.
"""

from __future__ import annotations

import uavtest.spec.loaders  # noqa: F401  (imported for the fork server's children)
from uavtest.engine.entry import command
from uavtest.px4.parameters import parameters

command()
parameters()
