"""Developer tools: speed and memory measurements, each printed as a ratio to a reference
measured in the same run. Not installed with the package (they need a source checkout):
``python -m benchmarks.speed.tracker_speed``, ``mimo-radar-bench perf`` from a checkout."""
