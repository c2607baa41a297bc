"""uavtest.engine."""
