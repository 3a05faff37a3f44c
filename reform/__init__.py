"""reform: F-formation detection (REFORM, GCFF) and its evaluation protocol.

Pure science: depends on numpy, scipy and scikit-learn only (Parquet and skops files are read
through optional imports of pyarrow and skops, which the project installs).

The public names below are loaded on first use (PEP 562), so that ``import reform`` stays light:
``reform.evaluate`` imports `reform.metrics` the first time it is looked up.
"""

from __future__ import annotations

from reform._lazy import lazy_exports

_EXPORTS = {
    "AnnotationModel": "reform.annotation",
    "PAPER_CHARACTERISATION": "reform.calibration",
    "Characterisation": "reform.calibration",
    "Comparison": "reform.calibration",
    "characterise_dataset": "reform.calibration",
    "compare": "reform.calibration",
    "GroupShapes": "reform.characterisation",
    "characterise": "reform.characterisation",
    "symmetry": "reform.characterisation",
    "tightness": "reform.characterisation",
    "load_dataset": "reform.datasets",
    "read_parquet": "reform.datasets",
    "write_parquet": "reform.datasets",
    "DataFormatError": "reform.datasets.errors",
    "Dante": "reform.dante",
    "Reform": "reform.detector",
    "check_detector": "reform.detector_checks",
    "Detector": "reform.detectors",
    "DetectorError": "reform.detectors",
    "DetectorInfo": "reform.detectors",
    "Option": "reform.detectors",
    "check_predictions": "reform.detectors",
    "detector_info": "reform.detectors",
    "detector_names": "reform.detectors",
    "fit_detector": "reform.detectors",
    "make_detector": "reform.detectors",
    "prepare_detector": "reform.detectors",
    "register_detector": "reform.detectors",
    "run_detector": "reform.detectors",
    "EVENT_KINDS": "reform.events",
    "GroupEvent": "reform.events",
    "GroupTracks": "reform.events",
    "group_events": "reform.events",
    "track_groups": "reform.events",
    "DEFAULT_FEATURES": "reform.features",
    "FEATURES": "reform.features",
    "FEATURE_SETS": "reform.features",
    "batch_pair_features": "reform.features",
    "effort_angle": "reform.features",
    "frame_pair_features": "reform.features",
    "frame_scale": "reform.features",
    "pair_indices": "reform.features",
    "HUMAN": "reform.frame",
    "KINDS": "reform.frame",
    "ROBOT": "reform.frame",
    "Dataset": "reform.frame",
    "Frame": "reform.frame",
    "Group": "reform.frame",
    "complete_partition": "reform.frame",
    "wrap_angle": "reform.frame",
    "FrameBlock": "reform.frame_block",
    "Gcff": "reform.gcff",
    "DominantSets": "reform.dominant_sets",
    "Gtcg": "reform.gtcg",
    "Hvff": "reform.hough",
    "MultiScaleHvff": "reform.hough",
    "Majority": "reform.majority",
    "Proximity": "reform.proximity",
    "jaccard_matrix": "reform.matching",
    "match_groups": "reform.matching",
    "T_ONE": "reform.metrics",
    "T_TWO_THIRDS": "reform.metrics",
    "THRESHOLDS": "reform.metrics",
    "Evaluation": "reform.metrics",
    "evaluate": "reform.metrics",
    "pair_labels": "reform.metrics",
    "NoisyPoses": "reform.perturb",
    "Perturbation": "reform.perturb",
    "TrackerNoise": "reform.perturb",
    "restrict_groups": "reform.perturb",
    "load_model": "reform.persistence",
    "save_model": "reform.persistence",
    "Settings": "reform.settings",
    "read_settings": "reform.settings",
    "write_settings": "reform.settings",
    "RECONSTRUCTIONS": "reform.reconstruction",
    "batch_correlation_labels": "reform.reconstruction",
    "batch_greedy_labels": "reform.reconstruction",
    "correlation_clustering": "reform.reconstruction",
    "greedy_reconstruction": "reform.reconstruction",
    "partition_from_labels": "reform.reconstruction",
    "relation_matrix": "reform.reconstruction",
    "time_blocks": "reform.splits",
    "time_split": "reform.splits",
    "KindScores": "reform.temporal",
    "TemporalEvaluation": "reform.temporal",
    "evaluate_events": "reform.temporal",
}

__version__ = "0.1.0"

__all__ = ["__version__", *sorted(_EXPORTS)]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
