"""reform: F-formation detection (REFORM, GCFF) and its evaluation protocol.

Pure science: depends on numpy, scipy and scikit-learn only (Parquet and skops files are read
through optional imports of pyarrow and skops, which the project installs).
"""

from __future__ import annotations

from reform.characterisation import GroupShapes, characterise, symmetry, tightness
from reform.datasets import load_dataset, read_parquet, write_parquet
from reform.datasets.errors import DataFormatError
from reform.frame import HUMAN, KINDS, ROBOT, Dataset, Frame, Group, complete_partition, wrap_angle
from reform.gcff import Gcff
from reform.majority import Majority
from reform.metrics import T_ONE, T_TWO_THIRDS, THRESHOLDS, Evaluation, evaluate, pair_labels

__version__ = "0.1.0"

__all__ = [
    "HUMAN",
    "KINDS",
    "ROBOT",
    "THRESHOLDS",
    "T_ONE",
    "T_TWO_THIRDS",
    "DataFormatError",
    "Dataset",
    "Evaluation",
    "Frame",
    "Gcff",
    "GroupShapes",
    "Group",
    "Majority",
    "__version__",
    "characterise",
    "complete_partition",
    "evaluate",
    "load_dataset",
    "pair_labels",
    "read_parquet",
    "symmetry",
    "tightness",
    "wrap_angle",
    "write_parquet",
]
