"""uavtest.store."""
