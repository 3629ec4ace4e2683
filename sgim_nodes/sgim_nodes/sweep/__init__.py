"""Sweeps: a YAML file of settings expanded into runs, each run through the node graph as a
Ray task, on this machine or on a cluster, resumable, with progress across the cluster.

- ``sweep_file``: the file format, its checks and its expansion into ``RunSpec``s (no Ray);
- ``results``: the results directory: what counts as a finished run, installing a run
  copied back from a worker, the status file (no Ray);
- ``task``: what a worker does for one run (scratch folder, run_experiment, tarball back);
- ``driver``: the command line: Ray start or join, submission, progress, summary.
"""
