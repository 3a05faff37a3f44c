"""Where the demo writes: its output folder and the names of what it holds.

Kept apart from the run (:mod:`sim.experiments.demo`) and its report
(:mod:`sim.experiments.demo_report`), which both write there, so that ``reform-sim demo --help``
names the default folder without loading MuJoCo or scikit-learn.
"""

from __future__ import annotations

__all__ = ["DEFAULT_OUT", "FIGURES", "MODEL", "RECORDINGS", "REPORT", "RESULTS", "SYNTHETIC"]

DEFAULT_OUT = "demo-output"  # the output folder, relative to the working directory
REPORT = "report.md"  # the Markdown report (demo_report)
RESULTS = "results.json"  # every number (demo_report)
MODEL = "model.skops"  # the saved REFORM model
RECORDINGS = "recordings"  # the .rrd files
FIGURES = "figures"  # the PNG plots
SYNTHETIC = "synthetic"  # the generated episodes, as Parquet
