"""uavtest.analysis: flight logs → trajectories, metrics, verdicts, averages, flakiness, plots.

Pure functions, no I/O inside, except the named edges ``ulog.read_ulog`` and ``plots.write_png``.
Modules (import them directly; this package imports nothing so that matplotlib and pyulog load
only where they are used):

- ``models``: Verdict, AssertionResult, FlightMetrics, MissionProgress, ReplicaResult, RunSummary
- ``trajectory``: Trajectory (t, x, y, z, heading; ``trajectory.csv``)
- ``ulog``: read_ulog, flight_window, trajectory_from_ulog, mission_progress_from_ulog
- ``geometry``: 3-D distance to oriented box obstacles, collides
- ``mission``: mission completion from waypoints reached in order
- ``similarity``: DTW and discrete Fréchet distance
- ``average``: average_trajectories → AverageTrajectory (``aggregate/average.csv``)
- ``verdict``: judge; ``flakiness``: summarize
- ``plots``: plot_run, plot_flight (PNG bytes), write_png
- ``report``: ``uavtest report``
"""
