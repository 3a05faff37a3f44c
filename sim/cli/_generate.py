"""``reform-sim generate``: a synthetic dataset of seeded episodes, as hive-partitioned Parquet."""

from __future__ import annotations

import argparse

from sim.cli._common import (
    add_backend_arguments,
    add_max_memory_argument,
    add_overrides_argument,
    add_sensor_arguments,
    add_view_argument,
)
from sim.cli._grammar import (
    add_quiet,
    add_recordings,
    add_seed,
    rename,
    run_loading,
    setter,
)
from sim.cli._numbers import ascii_float, ascii_int

DESCRIPTION = """\
Simulates EPISODES episodes of a scenario and writes them as hive-partitioned Parquet
(DIR/data/scenario=NAME/episode=K/part.parquet, which pandas, pyarrow, polars and DuckDB read
as they are) with a dataset card (DIR/dataset.json, and DIR/README.md with Hugging Face front
matter, so that the folder can be pushed to a hub as it is). DIR may be a store's URI
(s3://bucket/prefix, gs://..., any fsspec filesystem), credentials from the environment. Same
seed, same data; finished shards are skipped, so an interrupted run resumes and a larger
--episodes extends. The run is sized first (memory, disk, time; sim.sizing) and refused in one
line when it cannot fit this machine.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--scenario", metavar="NAME", help="scenario name (required unless --twin is given)"
    )
    parser.add_argument(
        "--twin",
        metavar="TWIN.json",
        help="a venue twin written by `reform-sim twin`: its scenario, options, annotation, rate "
        "and episodes (--episodes overrides its own)",
    )
    parser.add_argument(
        "--episodes", type=ascii_int, metavar="N", help="episodes (required unless --twin is given)"
    )
    add_seed(parser)
    parser.add_argument(
        "--out",
        required=True,
        metavar="DIR|URI",
        help="dataset folder, or a store's URI (s3://bucket/prefix, gs://..., any fsspec "
        "filesystem; credentials from the environment, e.g. AWS_ACCESS_KEY_ID)",
    )
    add_overrides_argument(parser)
    parser.add_argument(
        "--duration", type=ascii_float, default=None, metavar="SECONDS", help="episode length"
    )
    parser.add_argument(
        "--rate",
        type=ascii_float,
        default=None,
        metavar="HZ",
        help="output (annotation) rate (2 Hz)",
    )
    add_view_argument(parser)
    add_sensor_arguments(parser)
    add_backend_arguments(parser)
    add_recordings(parser, default=False, each="episode (episode=K.rrd)")
    rename(parser, "--save-recordings", "--recordings", setter("recordings", True), nargs=0)
    parser.add_argument(
        "--annotation",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="how the annotation records each episode (reform.annotation.AnnotationModel): "
        "orientation=body|head, directions=K|continuous, scale=F, scale_sd=F, position_noise=M, "
        "yaw_noise=RAD, dropout=P, min_group_seconds=S; repeatable; 'random' draws one model "
        "per episode from reform.annotation.ANNOTATION_RANGES",
    )
    add_quiet(parser)
    add_max_memory_argument(
        parser, holds="each worker holds the episode it writes (episodes do not stream)"
    )
    parser.set_defaults(handler=run_loading("sim.cli.generate:_run", "MuJoCo"))
