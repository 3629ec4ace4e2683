"""Analysis of a study (learners x seeds) from its bags alone: statistics, figures, tables.

Why bags only: a study's bags are its complete, self-describing record (they embed their message
definitions), so the comparison can be redone anywhere, without ROS and without the learner's
code, and it shows exactly what the node graph did.

  study.py       discover the runs, load each bag once into numpy arrays (cached per run)
  pooling.py     pool only what is alike: the runs' learner fingerprints compared
  statistics.py  means and 95 % intervals over seeds, pairwise tests, isolated-region coverage
  inference.py   Holm's correction, the smallest reachable p, effect sizes with intervals
  figures.py     error curves, landing histograms, interest-coloured region trees (PNG)
  report.py      the tables as named Markdown blocks: results.md's and the pages'
  cli.py         `analyze STUDY_DIR`: everything above into PNGs, results.md and results.json
  run_table.py   one run's columns as one compressed file: what the repository ships
  frames.py      runs as a tidy pandas table (``load_runs`` below)
"""


def load_runs(path, names=None):
    """The runs at `path` (run folders, shipped run tables, or a folder of either) as a tidy
    pandas table, one row per evaluation and benchmark goal (frames.py says the columns);
    only the runs called `names` when given."""
    from sgim_nodes.analysis.frames import load_runs as load

    return load(path, names)
