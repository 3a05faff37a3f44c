"""Loaders for F-formation datasets; every one returns a :class:`reform.Dataset` in metres."""

from __future__ import annotations

from reform.datasets.babble import load_babble
from reform.datasets.dante import load_dante, load_salsa
from reform.datasets.detect import FORMATS, LENGTH_UNITS, detect_format, load_dataset
from reform.datasets.errors import DataFormatError
from reform.datasets.fetch import (
    DatasetFile,
    FetchError,
    PublicDataset,
    cache_dir,
    fetch,
    is_fetched,
    local_datasets_dir,
    one_per_recording,
    registry,
    resolve,
)
from reform.datasets.gcff_mat import load_gcff
from reform.datasets.group_events import dataset_group_events
from reform.datasets.parquet import read_parquet, write_parquet
from reform.datasets.summary import summarise

__all__ = [
    "FORMATS",
    "LENGTH_UNITS",
    "DataFormatError",
    "DatasetFile",
    "FetchError",
    "PublicDataset",
    "cache_dir",
    "dataset_group_events",
    "detect_format",
    "fetch",
    "is_fetched",
    "load_babble",
    "load_dante",
    "load_dataset",
    "load_gcff",
    "load_salsa",
    "local_datasets_dir",
    "one_per_recording",
    "read_parquet",
    "registry",
    "resolve",
    "summarise",
    "write_parquet",
]
