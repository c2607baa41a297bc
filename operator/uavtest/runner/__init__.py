"""uavtest.runner."""
