"""uavtest: system-level UAV tests in simulation, N replicas in parallel."""

__version__ = "0.1.0"
