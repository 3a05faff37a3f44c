"""reform: F-formation detection (REFORM, GCFF) and its evaluation protocol.

Pure science: depends on numpy, scipy and scikit-learn only (Parquet and skops files are read
through optional imports of pyarrow and skops, which the project installs).
"""

from __future__ import annotations

from reform.datasets.errors import DataFormatError
from reform.frame import HUMAN, KINDS, ROBOT, Dataset, Frame, Group, complete_partition, wrap_angle

__version__ = "0.1.0"

__all__ = [
    "HUMAN",
    "KINDS",
    "ROBOT",
    "DataFormatError",
    "Dataset",
    "Frame",
    "Group",
    "__version__",
    "complete_partition",
    "wrap_angle",
]
