"""uavtest.analysis."""
