"""uavtest.sitl."""
