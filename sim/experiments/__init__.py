"""sim.experiments: the documented studies, each a run and the report that reads its result.

Built on the science (`reform`), the scenarios (`scenarios`) and the simulator core (`sim`);
nothing below imports this package, and only the command line (`sim.cli`) sits above it:

* ``reform-sim demo``: `demo` (its output folder's names in `demo_files`) → `demo_report`;
* ``reform-sim experiment sim2real``: `sim2real` → `sim2real_report`;
* ``reform-sim experiment hri``: `hri` (the views it can score in `hri_views`) → `hri_report`;
* ``reform-sim stress``: `stress` (its axes and grids in `stress_grid`) → `stress_report`;
* ``reform-sim calibrate``: `calibration` → `calibration_report`;
* ``reform-sim characterize``: `reform.calibration` (the science) → `characterisation_report`;
* ``reform-sim experiment paper``: `paper` → `paper_report`;
* ``reform-sim experiment gcff``: `gcff` → `gcff_report`;
* ``reform-sim benchmark``: `benchmark` → `benchmark_report`;

and what the reports share: `tables` (Markdown and text tables, percentages), `figures`
(matplotlib plots) and `report_files` (a page and its JSON written to disk). `demo_files`,
`hri_views` and `stress_grid` import neither MuJoCo nor scikit-learn, so that the command
line's help lists their choices fast.

The names below (each study's run and its result) are loaded on first use, so that
``import sim.experiments`` stays light; a study's report is imported from its module.
"""

from __future__ import annotations

from reform._lazy import lazy_exports

_EXPORTS = {
    "Benchmark": "sim.experiments.benchmark",
    "run_benchmark": "sim.experiments.benchmark",
    "CalibrationReport": "sim.experiments.calibration",
    "calibrate_scenarios": "sim.experiments.calibration",
    "DemoResult": "sim.experiments.demo",
    "run_demo": "sim.experiments.demo",
    "GcffComparison": "sim.experiments.gcff",
    "gcff_comparison": "sim.experiments.gcff",
    "HriExperiment": "sim.experiments.hri",
    "hri_experiment": "sim.experiments.hri",
    "PaperExperiment": "sim.experiments.paper",
    "paper_experiment": "sim.experiments.paper",
    "SimToReal": "sim.experiments.sim2real",
    "sim_to_real": "sim.experiments.sim2real",
    "StressGrid": "sim.experiments.stress_grid",
    "StressResults": "sim.experiments.stress",
    "run_stress": "sim.experiments.stress",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
