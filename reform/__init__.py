"""reform: F-formation detection (REFORM, GCFF) and its evaluation protocol.

Pure science: depends on numpy, scipy and scikit-learn only (Parquet and skops files are read
through optional imports of pyarrow and skops, which the project installs).
"""

from __future__ import annotations

from reform.calibration import (
    PAPER_CHARACTERISATION,
    Characterisation,
    Comparison,
    characterise_dataset,
    compare,
)
from reform.characterisation import GroupShapes, characterise, symmetry, tightness
from reform.datasets import load_dataset, read_parquet, write_parquet
from reform.datasets.errors import DataFormatError
from reform.detector import Reform
from reform.features import (
    DEFAULT_FEATURES,
    FEATURES,
    batch_pair_features,
    effort_angle,
    frame_pair_features,
    pair_indices,
)
from reform.frame import HUMAN, KINDS, ROBOT, Dataset, Frame, Group, complete_partition, wrap_angle
from reform.gcff import Gcff
from reform.majority import Majority
from reform.metrics import T_ONE, T_TWO_THIRDS, THRESHOLDS, Evaluation, evaluate, pair_labels
from reform.persistence import load_model, save_model
from reform.reconstruction import (
    RECONSTRUCTIONS,
    batch_greedy_labels,
    greedy_reconstruction,
    partition_from_labels,
    relation_matrix,
)
from reform.splits import time_blocks, time_split

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_FEATURES",
    "FEATURES",
    "HUMAN",
    "KINDS",
    "PAPER_CHARACTERISATION",
    "RECONSTRUCTIONS",
    "ROBOT",
    "THRESHOLDS",
    "T_ONE",
    "T_TWO_THIRDS",
    "Characterisation",
    "Comparison",
    "DataFormatError",
    "Dataset",
    "Evaluation",
    "Frame",
    "Gcff",
    "Group",
    "GroupShapes",
    "Majority",
    "Reform",
    "__version__",
    "batch_greedy_labels",
    "batch_pair_features",
    "characterise",
    "characterise_dataset",
    "compare",
    "complete_partition",
    "effort_angle",
    "evaluate",
    "frame_pair_features",
    "greedy_reconstruction",
    "load_dataset",
    "load_model",
    "pair_indices",
    "pair_labels",
    "partition_from_labels",
    "read_parquet",
    "relation_matrix",
    "save_model",
    "symmetry",
    "tightness",
    "time_blocks",
    "time_split",
    "wrap_angle",
    "write_parquet",
]
