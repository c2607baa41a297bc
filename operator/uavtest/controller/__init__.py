"""uavtest.controller."""
