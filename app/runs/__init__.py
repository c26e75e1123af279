"""Layer 4, runs: store keys, tasks, executors (local, Ray), sweeps, the results store, the
brute-force GQM run.

Imports quality, sim, model and the base modules; never reports, explorer or cli.
"""
