"""Synthetic datasets at scale: many seeded episodes of one scenario, as hive-partitioned Parquet.

A generated folder::

    DIR/
      README.md                                       the dataset card, for people, with Hugging
                                                      Face dataset-card front matter
      dataset.json                                    the same card, for programs: every
                                                      parameter, the seed, size and sha256 of
                                                      every shard, frame counts, group sizes
      data/scenario=<name>/episode=<k>/part.parquet   one shard per episode, the project's format,
                                                      its ground-truth group events in its
                                                      metadata (`reform.datasets.group_events`)
      recordings/episode=<k>.rrd                      with ``save_recordings``: one Rerun
                                                      recording per episode

Every shard is an ordinary file of the project's Parquet format (`reform.datasets.write_parquet`)
whose frames belong to the sequence ``"<name>-<k>"``, so the folder reads as one dataset with
``reform.datasets.read_parquet(DIR)`` (or ``load_dataset``, ``reform-sim train --data DIR``).
``DIR/data`` holds nothing but the shards (hive-partitioned by ``scenario`` and ``episode``, no
file inside has such a column), so other tools read it as it is: ``pandas.read_parquet(DIR /
"data")``, ``pyarrow.dataset.dataset(DIR / "data", partitioning="hive")``, polars and DuckDB
(``read_parquet('DIR/data/**/*.parquet', hive_partitioning = true)``); and the folder is laid
out as a Hugging Face dataset repository (card ``README.md`` with its ``configs``), so it can be
pushed to a hub as it is. A folder written before this layout (shards right under ``DIR``,
``scenario=<name>/...``) still reads, and a run resuming or extending it continues in its
layout, so that one folder never mixes the two.

**Seeds.** Episode ``k`` is simulated with its own seed, drawn from the master seed by
``numpy.random.SeedSequence(seed, spawn_key=(k,))`` (the ``k``-th child of
``SeedSequence(seed).spawn``): it depends on the master seed and ``k`` alone, never on the
backend, the number of workers, the order in which episodes finish or how many episodes the
dataset has. The same parameters therefore give byte-identical shards and cards.

**Resuming.** A shard is written to a temporary file and renamed into place
(`reform.atomic.atomic_path`), so it is either complete or absent: a run that is killed leaves no
half-written shard, and the next run with the same parameters skips the episodes already
written and simulates the rest. Each shard already there is first checked, from its footer alone,
to be its episode's (the episode, seed, sequence and parameters in its metadata, the values of
its ``sequence`` column): one copied or moved from another episode or dataset is refused, naming
the file, and nothing is changed. Each shard kept is then checked against the size and sha256
recorded when it was written (in its commit file ``_commits/episode=<k>.json``, written before
the shard is renamed into place, or in the card): a damaged one (altered, even in one value) is
named on stderr and made again, never vouched for; the card is written from these records only,
never from the files as they are. Asking for more episodes than a folder holds extends it. A folder
holding another dataset (a card with other parameters) or other files is refused before any work
starts, and so is a folder another run is writing.

**Parallelism.** Episodes run in batches (tiny tasks are slower in parallel) through
`sim.executor.Executor`: on local processes (joblib's loky backend, every core by default), or as
Ray remote tasks on a cluster (``backend="ray"``, ``address=...``; a batch whose worker died is
run again, up to `sim.executor.MAX_RETRIES` times). The address is probed before any work. Ray
workers writing to a folder on this machine send each shard back as bytes and this process
writes it, so the cluster needs no shared file system, only reform-sim installed on every node.

**Object storage.** ``out_dir`` may be a URI (``s3://bucket/prefix``, ``gs://…``, any fsspec
filesystem; `reform.datasets.store`), credentials from the environment. Every worker (local or Ray)
writes its shards there itself, each in two steps: the shard object (whole or absent), then its
commit object (`reform.datasets.store_dataset`); the finished run writes the card listing every
shard with its size and sha256, and deletes the commits. A resumed run skips the committed shards
whose objects match their recorded size and sha256 (each read back to be checked; a damaged one is
named on stderr) and writes the others again (an uncommitted shard object is never taken for done,
nor read). Two runs on one prefix are refused: the lock object ``.generate.lock`` is created only if
there is none (S3: ``If-None-Match: *``); one left by a killed run on this machine (its process
gone) is taken over with a conditional overwrite (``If-Match`` its ETag); the multipart uploads a
killed run left unfinished below the prefix (S3: objects of 100 MiB and more are sent in parts) are
aborted by the next run, and listed by `leftovers` until then. An unusable store (no credentials,
unreachable, no such bucket) or a prefix holding something else is refused in one line before any
work.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import functools
import gc
import hashlib
import json
import math
import os
import shlex
import shutil
import socket
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
import pyarrow.parquet as pq
from tqdm import tqdm

import scenarios
from reform import __version__
from reform.annotation import ANNOTATION_RANGES, AnnotationModel, draw_annotation
from reform.atomic import atomic_open, atomic_path
from reform.datasets.errors import DataFormatError
from reform.datasets.group_events import GROUP_EVENTS_KEY, count_kinds, group_events_record
from reform.datasets.parquet import CARD_JSON, FORMAT_VERSION, METADATA_KEY, write_parquet
from reform.datasets.store import Store, StoreError, is_uri, open_store
from reform.datasets.store_dataset import COMMITS_DIR, StoreFolder, commit_name
from reform.events import EVENT_KINDS
from reform.frame import Dataset, Frame
from reform.frame_block import FrameBlock
from reform.json_values import JsonError, parse_json
from reform.seeding import ANNOTATION, ANNOTATION_DRAW, derive_int, derive_rng
from scenarios import Scenario
from sim import sizing
from sim.episode import (
    DEFAULT_RATE_HZ,
    episode_blocks,
    estimate_episode,
    prepare,
    scene_spec,
    simulate_episode,
)
from sim.executor import BACKENDS, Executor, cpu_count
from sim.sensor import Sensor
from sim.ticking import ticking
from sim.world import steps_per_frame, whole_step_rates

__all__ = [
    "BACKENDS",
    "CARD_JSON",
    "CARD_MARKDOWN",
    "DATA_DIR",
    "VIEWS",
    "FolderRefused",
    "GenerationReport",
    "GenerationSpec",
    "ShardSummary",
    "episode_seed",
    "folder_layout",
    "generate_dataset",
    "leftovers",
    "read_card",
    "shard_path",
]

VIEWS = ("truth", "robot")  # ground truth, or what the robot's head sensor observes
CARD_MARKDOWN = "README.md"  # the dataset card, for people
CARD_VERSION = 1
SHARD_FILE = "part.parquet"
DATA_DIR = "data"  # the shards' folder (the hive root); "" in folders of the first layout
CARD_LICENSE = "mit"  # the card's license: the toolkit's own (edit it before publishing)
# Hugging Face size categories (number of rows): upper bound -> name.
SIZE_CATEGORIES = (
    (1_000, "n<1K"),
    (10_000, "1K<n<10K"),
    (100_000, "10K<n<100K"),
    (1_000_000, "100K<n<1M"),
    (10_000_000, "1M<n<10M"),
    (100_000_000, "10M<n<100M"),
    (1_000_000_000, "100M<n<1B"),
)
RECORDINGS_DIR = "recordings"
LOCK_FILE = ".generate.lock"
# Environment variables the stores' libraries read (botocore, google-auth, azure, fsspec), and
# the stores' deadline (reform.datasets.store.TIMEOUT_VARIABLE).
STORE_ENVIRONMENT = ("AWS_", "GOOGLE_", "GCE_", "AZURE_", "FSSPEC_", "REFORM_SIM_STORE_")
TASKS_PER_WORKER = 4  # batches per worker, so that uneven episodes still balance
MAX_EPISODES_PER_TASK = 16  # episodes per batch at most (progress stays live)
RANDOM_ANNOTATION = "random"  # GenerationSpec.annotation: one model drawn per episode
SHOWN_PROBLEMS = 3  # shards named in the error when several are not where they belong
VERIFY_BATCH = 16  # shards of a store fetched at once to be checked on resume


def episode_seed(seed: int, episode: int) -> int:
    """The seed of episode ``episode`` of a dataset with master seed ``seed``:
    ``reform.seeding.derive_int(seed, episode)``, the first 63 bits of
    ``SeedSequence(seed, spawn_key=(episode,))``, the ``episode``-th child of
    ``SeedSequence(seed).spawn(...)``."""
    return derive_int(seed, episode)


def shard_path(
    out_dir: str | os.PathLike[str], scenario: str, episode: int, *, data_dir: str | None = None
) -> Path:
    """Where episode ``episode`` of ``scenario`` lives in a generated folder.

    Args:
        out_dir: the dataset folder.
        scenario: the scenario's name.
        episode: the episode index.
        data_dir: the shards' folder inside ``out_dir``: ``"data"``, or ``""`` for a folder of
            the first layout (shards right under ``out_dir``); None for the layout of the folder
            as it is (``"data"`` for a new one).
    """
    folder = Path(out_dir)
    data = folder_layout(folder) if data_dir is None else data_dir
    return folder / data / _relative_shard(scenario, episode)


def _relative_shard(scenario: str, episode: int) -> str:
    """A shard's path under the hive root (`ShardSummary.path`; shards carry it)."""
    return f"scenario={scenario}/episode={int(episode)}/{SHARD_FILE}"


def folder_layout(out_dir: str | os.PathLike[str]) -> str:
    """The shards' folder of a generated folder: ``"data"``, or ``""`` when the folder is of the
    first layout (shards right under it, ``scenario=<name>/...``; its card says so even before a
    shard is written). A new or empty folder gets ``"data"``.

    Raises:
        ValueError: the folder holds shards in both layouts.
    """
    folder = Path(out_dir)
    if not folder.is_dir():
        return DATA_DIR
    old = next(folder.glob("scenario=*"), None)
    if old is not None:
        if (folder / DATA_DIR).exists():
            raise FolderRefused(
                folder,
                f"holds shards in two layouts ({old.name}/ and {DATA_DIR}/): "
                f"expected one; move {old.name}/ and its kin under {DATA_DIR}/ or use another "
                "folder"
            )
        return ""
    try:
        card = read_card(folder)
    except ValueError:
        card = None
    if card is not None and str(card.get("layout", "")).startswith("scenario="):
        return ""
    return DATA_DIR


class FolderRefused(ValueError):
    """A dataset folder refused before any work: another dataset, foreign files, shards in
    two layouts, another run writing it.

    ``str`` names the folder as the library's parameter (``out_dir /data/x holds ...``);
    :meth:`message` names it as the caller does, a command's flag (``--out /data/x holds
    ...``).

    Attributes:
        folder: the folder (a path or a store's URI), as given.
    """

    def __init__(self, folder: str | os.PathLike[str], detail: str) -> None:
        self.folder = str(folder)
        self._detail = detail
        super().__init__(self.message())

    def message(self, name: str = "out_dir") -> str:
        """The message, the folder named ``name`` (``"--out"``)."""
        gap = "" if self._detail.startswith(":") else " "
        return f"{name} {self.folder}{gap}{self._detail}"


@dataclass(frozen=True)
class _Folder:
    """Where a run writes: the dataset folder and its shards' folder (`folder_layout`)."""

    out: Path
    data: str = DATA_DIR

    @property
    def root(self) -> Path:
        """The hive root: ``scenario=<name>/episode=<k>/part.parquet`` below it."""
        return self.out / self.data

    def shard(self, scenario: str, episode: int) -> Path:
        return self.root / _relative_shard(scenario, episode)

    def listed(self, summary: ShardSummary) -> str:
        """The shard's path as the card lists it: relative to the dataset folder."""
        return f"{self.data}/{summary.path}" if self.data else summary.path


def _recording_name(episode: int) -> str:
    """The episode's recording, relative to the dataset folder."""
    return f"{RECORDINGS_DIR}/episode={int(episode)}.rrd"


def _recording_path(out_dir: Path, episode: int) -> Path:
    return out_dir / _recording_name(episode)


def _json_value(name: str, value: Any) -> Any:
    """``value`` as JSON gives it back (tuples become lists), or a ValueError naming it."""
    try:
        return json.loads(json.dumps(value, allow_nan=False, sort_keys=True))
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"{name} must be JSON values (numbers, strings, booleans, lists), got {value!r}"
        ) from exc


def _check_int(name: str, value: Any, *, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an int >= {minimum}, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be an int >= {minimum}, got {value}")
    return int(value)


def _check_positive(name: str, value: Any, unit: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a positive number ({unit}), got {value!r}") from exc
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{name} must be a positive number ({unit}), got {value!r}")
    return number


@dataclass(frozen=True, eq=False)
class GenerationSpec:
    """Everything that fixes a generated dataset's data (not how or where it is computed).

    Attributes:
        scenario: registered scenario name.
        options: the scenario's option overrides (JSON values), as given to ``scenarios.make``.
        seed: master seed, a non-negative int.
        view: ``"truth"`` (ground truth) or ``"robot"`` (the robot's head sensor view).
        sensor: the sensor model of the robot view (``None`` for the truth view).
        rate: output (annotation) rate, Hz.
        duration: episode length, seconds; ``None`` for each episode's natural length.
        annotation: how the dataset's annotation records each episode (`reform.annotation`):
            an `AnnotationModel` (or its settings as a mapping), ``"random"`` for one drawn per
            episode from `reform.annotation.ANNOTATION_RANGES`, or ``None`` for the frames as
            simulated.
    """

    scenario: str
    options: Mapping[str, Any] = field(default_factory=dict)
    seed: int = 0
    view: str = "truth"
    sensor: Any = None
    rate: float = DEFAULT_RATE_HZ
    duration: float | None = None
    annotation: AnnotationModel | str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.scenario, str) or not self.scenario:
            raise ValueError(f"scenario must be a scenario name, got {self.scenario!r}")
        if not isinstance(self.options, Mapping):
            raise ValueError(
                f"options must be a mapping of option name to value, got {self.options!r}"
            )
        options = _json_value("options", dict(self.options))
        object.__setattr__(self, "options", MappingProxyType(options))
        object.__setattr__(self, "seed", _check_int("seed", self.seed, minimum=0))
        if self.view not in VIEWS:
            raise ValueError(f"view must be one of {VIEWS}, got {self.view!r}")
        object.__setattr__(self, "sensor", _sensor(self.view, self.sensor))
        rate = _check_positive("rate", self.rate, "Hz")
        try:  # the world records frames on its control steps only
            steps_per_frame(rate)
        except ValueError:
            raise ValueError(f"rate must be {whole_step_rates()}, got {rate:g}") from None
        object.__setattr__(self, "rate", rate)
        if self.duration is not None:
            duration = _check_positive("duration", self.duration, "seconds")
            if duration * rate < 1.0 - 1e-9:
                raise ValueError(
                    f"duration {duration:g} s holds no frame at {rate:g} Hz: it must be >= "
                    f"{1.0 / rate:g} s"
                )
            object.__setattr__(self, "duration", duration)
        object.__setattr__(self, "annotation", _annotation(self.annotation))

    def parameters(self) -> dict[str, Any]:
        """The parameters as the card records them (JSON values); two runs with equal
        parameters (and package version) write the same data."""

        return {
            "scenario": self.scenario,
            "options": dict(self.options),
            "seed": self.seed,
            "view": self.view,
            "sensor": None
            if self.sensor is None
            else _json_value("sensor", dataclasses.asdict(self.sensor)),
            "rate_hz": self.rate,
            "duration_s": self.duration,
            "package_version": f"reform-sim {__version__}",
            "format_version": FORMAT_VERSION,
            "seed_rule": (
                "episode k: the first 63 bits of numpy SeedSequence(seed, spawn_key=(k,))"
            ),
        } | self._annotation_parameters()

    def _annotation_parameters(self) -> dict[str, Any]:
        """The annotation as the card records it; nothing for the frames as simulated (so that
        such datasets keep the cards they had)."""
        if self.annotation is None:
            return {}
        if self.annotation == RANDOM_ANNOTATION:
            return {
                "annotation": RANDOM_ANNOTATION,
                "annotation_ranges": {k: list(v) for k, v in ANNOTATION_RANGES.items()},
            }
        return {"annotation": self.annotation.to_json()}

    def annotation_of(self, episode: int) -> AnnotationModel | None:
        """The annotation model of episode ``episode`` and the generator that applies it."""
        if self.annotation is None:
            return None
        if self.annotation == RANDOM_ANNOTATION:
            return draw_annotation(derive_rng(episode_seed(self.seed, episode), ANNOTATION_DRAW))
        return self.annotation


def _annotation(value: Any) -> AnnotationModel | str | None:
    """``value`` as a GenerationSpec's annotation: None for the identity."""
    if value is None or value == RANDOM_ANNOTATION:
        return value
    if isinstance(value, Mapping):
        value = AnnotationModel(**value)
    if not isinstance(value, AnnotationModel):
        raise ValueError(
            f"annotation must be an AnnotationModel, its settings or {RANDOM_ANNOTATION!r}, got "
            f"{value!r}"
        )
    return None if value.identity else value


def _sensor(view: str, sensor: Any) -> Any:
    """The Sensor of the robot view (defaults when ``None``); an error for the truth view."""
    if view == "truth":
        if sensor is not None:
            raise ValueError(
                "sensor options apply to view='robot' only, got sensor options with view='truth'"
            )
        return None

    if sensor is None:
        return Sensor()
    if isinstance(sensor, Sensor):
        return sensor
    if isinstance(sensor, Mapping):
        known = {f.name for f in dataclasses.fields(Sensor)}
        unknown = sorted(set(sensor) - known)
        if unknown:
            raise ValueError(f"sensor options must be among {sorted(known)}, got {unknown}")
        return Sensor(**sensor)
    raise ValueError(
        f"sensor must be a sim.Sensor, a mapping of its fields or None, got {sensor!r}"
    )


@dataclass(frozen=True)
class ShardSummary:
    """What one shard holds.

    Attributes:
        episode: episode index ``k``.
        seed: the episode's seed (see `episode_seed`).
        path: the shard's path relative to the dataset folder.
        sequence: the sequence name of its frames.
        frames: frames in the shard.
        annotated_frames: frames with ground-truth groups.
        rows: people (and robot) entries over all frames.
        duration: the episode's simulated length, seconds.
        group_sizes: size -> number of groups of that size over the annotated frames, counting
            everyone (people alone are groups of size 1; the robot counts as a member).
        group_events: kind -> number of ground-truth group events of that kind
            (`reform.events.EVENT_KINDS`, zeros included) the shard stores; None for a shard
            written before the events were stored.
    """

    episode: int
    seed: int
    path: str
    sequence: str
    frames: int
    annotated_frames: int
    rows: int
    duration: float
    group_sizes: Mapping[int, int]
    group_events: Mapping[str, int] | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "episode": self.episode,
            "seed": self.seed,
            "path": self.path,
            "sequence": self.sequence,
            "frames": self.frames,
            "annotated_frames": self.annotated_frames,
            "rows": self.rows,
            "duration_s": self.duration,
            "group_sizes": {str(k): v for k, v in sorted(self.group_sizes.items())},
        } | ({} if self.group_events is None else {"group_events": dict(self.group_events)})

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ShardSummary:
        return cls(
            episode=int(data["episode"]),
            seed=int(data["seed"]),
            path=str(data["path"]),
            sequence=str(data["sequence"]),
            frames=int(data["frames"]),
            annotated_frames=int(data["annotated_frames"]),
            rows=int(data["rows"]),
            duration=float(data["duration_s"]),
            group_sizes={int(k): int(v) for k, v in dict(data["group_sizes"]).items()},
            group_events=None
            if data.get("group_events") is None
            else _kinds_in_order(data["group_events"]),
        )


def _kinds_in_order(counts: Mapping[str, Any]) -> dict[str, int]:
    """Counts per event kind in `reform.events.EVENT_KINDS` order, whatever order they came in
    (a commit file sorts its keys): the card lists them so, byte for byte, however it was made."""
    order = {kind: k for k, kind in enumerate(EVENT_KINDS)}
    items = sorted(dict(counts).items(), key=lambda kv: (order.get(kv[0], len(order)), kv[0]))
    return {str(k): int(v) for k, v in items}


@dataclass(frozen=True, eq=False)
class GenerationReport:
    """What a call of `generate_dataset` did.

    Attributes:
        out_dir: the dataset folder (its URI in a store).
        spec: the parameters.
        episodes: episodes in the dataset.
        generated: episodes simulated by this call.
        skipped: episodes found finished and left alone.
        shards: every shard of the dataset, by episode.
        seconds: wall-clock time of this call, seconds.
        backend: ``"local"`` or ``"ray"``.
        n_jobs: worker processes used (local), or the cluster's CPUs (Ray).
        card: path (URI) of the JSON card; ``card_markdown`` of the Markdown one.
        check_seconds: wall-clock time spent checking the shards already there (each against
            the size and sha256 recorded when it was written), seconds.
    """

    out_dir: Path | str
    spec: GenerationSpec
    episodes: int
    generated: tuple[int, ...]
    skipped: tuple[int, ...]
    shards: tuple[ShardSummary, ...]
    seconds: float
    backend: str
    n_jobs: int
    card: Path | str
    card_markdown: Path | str
    check_seconds: float = 0.0

    @property
    def frames(self) -> int:
        return sum(s.frames for s in self.shards)

    @property
    def annotated_frames(self) -> int:
        return sum(s.annotated_frames for s in self.shards)

    @property
    def generated_annotated_frames(self) -> int:
        """Annotated frames in the shards this call wrote."""
        done = set(self.generated)
        return sum(s.annotated_frames for s in self.shards if s.episode in done)


# ------------------------------------------------------------------------------------------
# One episode (runs in the workers)


def _sequence_name(scenario: str, episode: int) -> str:
    return f"{scenario}-{int(episode)}"


def _summary(
    spec: GenerationSpec,
    episode: int,
    frames: int,
    annotated: int,
    rows: int,
    sizes: Mapping[int, int],
    events: Mapping[str, Any] | None = None,
) -> ShardSummary:
    """A shard's summary; ``events``: the group events it stores (`group_events_record`)."""
    return ShardSummary(
        episode=int(episode),
        seed=episode_seed(spec.seed, episode),
        path=_relative_shard(spec.scenario, episode),
        sequence=_sequence_name(spec.scenario, episode),
        frames=frames,
        annotated_frames=annotated,
        rows=rows,
        duration=frames / spec.rate,
        group_sizes=dict(sorted(sizes.items())),
        group_events=None if events is None else count_kinds(events),
    )


def _summarise_frames(
    spec: GenerationSpec, episode: int, frames: Sequence[Frame], events: Mapping[str, Any]
) -> ShardSummary:
    sizes: Counter[int] = Counter()
    annotated = rows = 0
    for frame in frames:
        n = frame.n_people
        rows += n
        if frame.groups is None:
            continue
        annotated += 1
        grouped = 0
        for group in frame.groups:
            sizes[len(group)] += 1
            grouped += len(group)
        if n > grouped:
            sizes[1] += n - grouped
    return _summary(spec, episode, len(frames), annotated, rows, sizes, events)


def _summarise_block(
    spec: GenerationSpec,
    episode: int,
    block: FrameBlock,
    events: Mapping[str, Any],
    groups: Sequence[tuple[tuple[int, ...], ...] | None] | None = None,
) -> ShardSummary:
    """As `_summarise_frames`, for the frames of a block, without making them. ``groups``:
    ``block.present_groups()``, when already worked out.

    `FrameBlock.present_groups` gives one object for a run of instants whose groups and
    people do not change: each run is counted once, times its length."""
    if groups is None:
        groups = block.present_groups()
    counts = block.present.sum(axis=1).tolist()
    runs: list[tuple[tuple[tuple[int, ...], ...], int, int]] = []  # (groups, people, instants)
    for frame_groups, people in zip(groups, counts, strict=True):
        if frame_groups is None:
            continue
        if runs and runs[-1][0] is frame_groups and runs[-1][1] == people:
            runs[-1] = (frame_groups, people, runs[-1][2] + 1)
        else:
            runs.append((frame_groups, people, 1))
    sizes: Counter[int] = Counter()
    for frame_groups, people, instants in runs:
        for group in frame_groups:
            sizes[len(group)] += instants
        alone = people - sum(len(group) for group in frame_groups)
        if alone > 0:
            sizes[1] += alone * instants
    annotated = sum(instants for _, _, instants in runs)
    return _summary(spec, episode, len(block), annotated, sum(counts), sizes, events)


def _shard_metadata(
    spec: GenerationSpec, summary: ShardSummary, made: Any, events: Mapping[str, Any]
) -> dict[str, Any]:
    """What a shard carries besides its frames: the parameters, its episode, its scenario, and
    its ground-truth group events (`reform.datasets.group_events`)."""
    return {
        "generator": "reform-sim generate",
        "parameters": spec.parameters(),
        "episode": summary.to_json(),
        "scenario": {
            "name": made.name,
            "seed": made.seed,
            "options": _json_value("scenario options", dict(made.options)),
            "natural_duration_s": made.duration,
            "room_m": list(made.stage.room),
        },
        GROUP_EVENTS_KEY: dict(events),
    }


@contextlib.contextmanager
def _collector_spared() -> Iterator[None]:
    """Python's cycle collector leaves alone, while the block runs, every object that exists
    when it starts (`gc.freeze`; `gc.unfreeze` after it). Those are mostly the modules imported
    (numpy, MuJoCo, pyarrow: some 170,000 objects), which a full collection would otherwise walk
    each time making a scenario's script sets one off; what the block makes is collected as
    usual. A caller that froze objects itself keeps its own arrangement."""
    if gc.get_freeze_count():
        yield
        return
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def _write_episode(
    spec: GenerationSpec,
    folder: _Folder,
    episode: int,
    *,
    save_recordings: bool,
    made: Scenario | None = None,
) -> ShardSummary:
    """`_simulate_and_write`, its errors naming the episode and its seed (to reproduce it)."""
    try:
        with _collector_spared():
            return _simulate_and_write(
                spec, folder, episode, save_recordings=save_recordings, made=made
            )
    except ValueError as exc:
        raise ValueError(
            f"episode {episode} of {spec.scenario} (episode seed {episode_seed(spec.seed, episode)}"
            f", master seed {spec.seed}) failed: {exc}"
        ) from exc


def _simulate_and_write(
    spec: GenerationSpec,
    folder: _Folder,
    episode: int,
    *,
    save_recordings: bool,
    made: Scenario | None = None,
) -> ShardSummary:
    """Simulates one episode and writes its recording (if asked) and then its shard.

    The ground-truth view without a recording or an annotation model takes the fast path: poses
    in blocks of arrays (`sim.episode.episode_blocks`) written as columns
    (`reform.datasets.write_parquet` of a `reform.FrameBlock`), no `Frame` per instant. The file
    is the one the frame path writes, byte for byte. An annotation model records the simulated
    frames as it says; the recording, when asked for, is of the simulation itself.

    ``made``: the episode's scenario when it is already made (episode 0's, made by
    `_check_scenario` in this process), else it is made here.
    """

    if made is None:
        made = prepare(spec.scenario, seed=episode_seed(spec.seed, episode), options=spec.options)
    sequence = _sequence_name(spec.scenario, episode)
    source = f"reform-sim generate --scenario {spec.scenario} --seed {spec.seed}"
    path = folder.shard(spec.scenario, episode)
    annotation = spec.annotation_of(episode)
    if spec.view == "truth" and not save_recordings and annotation is None:
        block = FrameBlock.concatenate(
            list(episode_blocks(made, duration=spec.duration, rate=spec.rate, sequence=sequence))
        )
        groups = block.present_groups()
        events = group_events_record(partitions=groups, times=block.time, sequences=block.sequence)
        summary = _summarise_block(spec, episode, block, events, groups)
        with atomic_path(path) as tmp:
            write_parquet(
                block,
                tmp,
                name=spec.scenario,
                source=source,
                metadata=_shard_metadata(spec, summary, made, events),
            )
            _write_commit(folder, summary, _file_entry(tmp))
        return summary
    result = simulate_episode(
        made,
        duration=spec.duration,
        rate=spec.rate,
        view=spec.view,
        sensor=spec.sensor,
        sequence=sequence,
    )
    if save_recordings:  # the simulated episode, before any annotation model
        _record(spec, episode, result, _recording_path(folder.out, episode))
    frames = result.dataset.frames
    metadata: dict[str, Any] = {}
    if annotation is not None:  # as the annotation records it (reform.annotation)
        rng = derive_rng(episode_seed(spec.seed, episode), ANNOTATION)
        frames = annotation.apply(frames, rng)
        metadata["annotation"] = annotation.to_json()
    events = group_events_record(frames)
    summary = _summarise_frames(spec, episode, frames, events)
    dataset = Dataset(
        frames=frames,
        name=spec.scenario,
        source=source,
        metadata=_shard_metadata(spec, summary, made, events) | metadata,
    )
    with atomic_path(path) as tmp:
        write_parquet(dataset, tmp)
        _write_commit(folder, summary, _file_entry(tmp))
    return summary


def _write_commit(folder: _Folder, summary: ShardSummary, files: Mapping[str, Any]) -> None:
    """Records a shard's size and sha256 (``files``) in its commit file, before the shard is
    renamed into place: a shard in the folder always has its checksum recorded, and a resumed
    run checks it against that record (`_verified_shards`)."""
    entry = {**summary.to_json(), "path": folder.listed(summary), **files}
    with atomic_open(folder.out / commit_name(summary.episode), "w", encoding="utf-8") as handle:
        json.dump(entry, handle, sort_keys=True)


def _record(spec: GenerationSpec, episode: int, result: Any, path: Path) -> None:
    """One Rerun recording of the episode: the scene, everyone, the groups, the robot's view."""
    from sim.recording import FieldOfView, record_episode  # here: only a recording needs Rerun

    # Rerun writes to a path ending in .rrd: a hidden scratch folder beside it, then a rename.
    path.parent.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
    try:
        record_episode(
            scratch / path.name,
            result.truth,
            observed=result.dataset.frames if spec.view == "robot" else None,
            events=result.events,
            model=result.model,
            seed=episode_seed(spec.seed, episode),
            name=_sequence_name(spec.scenario, episode),
            field_of_view=FieldOfView.of(spec.sensor),
        )
        os.replace(scratch / path.name, path)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _run_batch(
    episodes: Sequence[int],
    spec: GenerationSpec,
    folder: _Folder,
    save_recordings: bool,
    first: Scenario | None = None,
) -> list[ShardSummary]:
    """A batch of episodes, written straight into ``folder`` (local workers). ``first``:
    episode 0's made scenario, when the batch runs in the process that made it for its
    checks (`_check_scenario`): it is not made a second time."""
    return [
        _write_episode(
            spec, folder, k, save_recordings=save_recordings, made=first if k == 0 else None
        )
        for k in episodes
    ]


def _run_batch_bytes(
    episodes: Sequence[int], spec: GenerationSpec, save_recordings: bool
) -> list[tuple[ShardSummary, bytes, bytes | None]]:
    """A batch of episodes, sent back as file contents (Ray workers, maybe on other machines)."""
    return list(_episode_files(episodes, spec, save_recordings))


def _run_batch_store(
    episodes: Sequence[int], spec: GenerationSpec, uri: str, save_recordings: bool
) -> list[tuple[ShardSummary, dict[str, Any]]]:
    """A batch of episodes written to the store at ``uri`` by this worker: each shard, then its
    commit. Returns each summary with its shard's ``bytes`` and ``sha256``."""
    store = open_store(uri, check=False)
    out = []
    with contextlib.closing(_episode_files(episodes, spec, save_recordings)) as made:
        for summary, shard, recording in made:
            if recording is not None:
                store.write(_recording_name(summary.episode), recording)
            listed = f"{DATA_DIR}/{summary.path}"
            store.write(listed, shard)
            files = {"bytes": len(shard), "sha256": hashlib.sha256(shard).hexdigest()}
            entry = {**summary.to_json(), "path": listed, **files}
            store.write(commit_name(summary.episode), json.dumps(entry, sort_keys=True).encode())
            out.append((summary, files))
    return out


def _episode_files(
    episodes: Sequence[int], spec: GenerationSpec, save_recordings: bool
) -> Iterator[tuple[ShardSummary, bytes, bytes | None]]:
    """Each episode of a batch simulated in a scratch folder, as its summary and the contents
    of its shard and of its recording (None unless asked for): for workers that do not write
    into the dataset folder. One episode's files are held at a time."""
    with tempfile.TemporaryDirectory(prefix="reform-sim-generate-") as scratch:
        folder = _Folder(Path(scratch))
        for k in episodes:
            summary = _write_episode(spec, folder, k, save_recordings=save_recordings)
            shard = _take(folder.root / summary.path)
            recording = _take(_recording_path(folder.out, k)) if save_recordings else None
            yield summary, shard, recording


def _take(path: Path) -> bytes:
    """The file's contents; the file removed."""
    content = path.read_bytes()
    path.unlink()
    return content


# ------------------------------------------------------------------------------------------
# The dataset: its card, what it may hold


def read_card(out_dir: str | os.PathLike[str]) -> dict[str, Any] | None:
    """The JSON card of a generated folder, or ``None`` when it has none.

    Raises:
        ValueError: the card exists but is not a reform-sim dataset card.
    """
    path = Path(out_dir) / CARD_JSON
    if not path.is_file():
        return None
    try:
        card = parse_json(path.read_bytes())
    except OSError as exc:
        raise ValueError(
            f"{path}: expected a readable reform-sim dataset card, found {exc.strerror or exc}"
        ) from None
    except JsonError as exc:
        raise ValueError(
            f"{path}: expected a reform-sim dataset card (JSON), found {exc}"
        ) from None
    return _checked_card(card, path)


def _checked_card(card: Any, where: object) -> dict[str, Any]:
    """``card`` (parsed JSON) when it is a reform-sim dataset card, else a ValueError naming
    ``where`` and the field: its parameters an object, its version one this version reads,
    its episodes a count, ``complete`` true or false. A run resuming it rewrites it, so a field
    it would rewrite is checked here rather than silently mended."""
    if not isinstance(card, dict) or not isinstance(card.get("parameters"), dict):
        raise ValueError(
            f"{where}: expected a reform-sim dataset card with a 'parameters' object, "
            f"got {type(card).__name__}"
        )
    version = card.get("card_version", CARD_VERSION)
    episodes = card.get("episodes", 0)
    complete = card.get("complete", False)
    checks = (
        (
            "card_version",
            version,
            _is_int(version) and 1 <= version <= CARD_VERSION,
            f"an integer from 1 to {CARD_VERSION}",
        ),
        ("episodes", episodes, _is_int(episodes) and episodes >= 0, "a count of episodes"),
        ("complete", complete, isinstance(complete, bool), "true or false"),
    )
    for name, value, ok, expected in checks:
        if not ok:
            raise ValueError(f"{where}: field {name!r}: expected {expected}, found {value!r}")
    return card


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_ours(name: str) -> bool:
    """Entries a generated folder may hold besides its shards."""
    ours = (CARD_JSON, CARD_MARKDOWN, LOCK_FILE, RECORDINGS_DIR, DATA_DIR, COMMITS_DIR)
    return name in ours or name.startswith(("scenario=", "."))


def _check_folder(out_dir: Path, parameters: Mapping[str, Any], episodes: int) -> None:
    """Refuses a folder that holds anything but a dataset with these parameters."""
    if out_dir.exists() and not out_dir.is_dir():
        raise FolderRefused(out_dir, "is a file: expected a folder")
    if not out_dir.exists():
        return
    _check_contents(
        str(out_dir),
        [p.name for p in out_dir.iterdir()],
        read_card(out_dir),
        parameters,
        episodes,
        things="files",
        instead="an empty or new folder, or one made by reform-sim generate",
    )
    _check_shard_files(out_dir, parameters, episodes)


def _check_shard_files(out_dir: Path, parameters: Mapping[str, Any], episodes: int) -> None:
    """Refuses a dataset folder holding a Parquet file that is none of its shards: every reader
    refuses a dataset with a file its card does not list, so the run would end with a dataset
    no command reads."""
    root = out_dir / folder_layout(out_dir)
    if not root.is_dir():
        return
    scenario = parameters.get("scenario")
    ours = {root / _relative_shard(str(scenario), k) for k in range(episodes)}
    for path in sorted(root.rglob("*.parquet")):
        relative = path.relative_to(out_dir)
        if path not in ours and not any(part.startswith(".") for part in relative.parts):
            raise FolderRefused(
                out_dir,
                f"holds {relative}, which is none of the shards of this "
                f"dataset ({episodes} episodes of {scenario}, as "
                f"{_relative_shard(str(scenario), 0)} ...): remove it or use another folder"
            )


def _check_contents(
    out: str,
    names: Iterable[str],
    card: Mapping[str, Any] | None,
    parameters: Mapping[str, Any],
    episodes: int,
    *,
    things: str,
    instead: str,
    also_ours: tuple[str, ...] = (),
) -> None:
    """Refuses a dataset folder or store prefix ``out`` whose top-level ``names`` are anything
    but this dataset (``things``, ``instead``: the words of the messages)."""
    if card is None:
        foreign = sorted(n for n in names if not n.startswith("."))
        if foreign:
            shown = ", ".join(foreign[:5]) + (", ..." if len(foreign) > 5 else "")
            raise FolderRefused(
                out,
                f"holds {things} but no dataset card ({CARD_JSON}): expected "
                f"{instead}, found {shown}"
            )
        return
    _check_card(out, card, parameters, episodes)
    extra = sorted(n for n in names if not _is_ours(n) and n not in also_ours)
    if extra:
        raise FolderRefused(
            out,
            f"holds {things} that are not part of a generated dataset: "
            f"{', '.join(extra[:5])}"
        )


def _check_card(
    out: str, card: Mapping[str, Any], parameters: Mapping[str, Any], episodes: int
) -> None:
    """Refuses a card of another dataset, or of more episodes than asked for (``out``: the
    folder or URI, for the message)."""
    theirs = card["parameters"]
    differing = sorted(
        k for k in set(theirs) | set(parameters) if theirs.get(k) != parameters.get(k)
    )
    if differing:
        details = "; ".join(
            f"{k}: folder has {json.dumps(theirs.get(k))}, "
            f"asked for {json.dumps(parameters.get(k))}"
            for k in differing
        )
        raise FolderRefused(
            out,
            f"holds another dataset (its {CARD_JSON} differs in "
            f"{', '.join(differing)}): {details}. Use another folder, or the same parameters "
            "to resume it"
        )
    held = int(card.get("episodes", 0))
    if episodes < held:
        raise FolderRefused(
            out,
            f"holds a dataset of {held} episodes, asked for "
            f"{episodes}; ask for at least {held} (more extends it) or use another folder"
        )


# ------------------------------------------------------------------------------------------
# A prefix in a store: card, lock, committed shards


def _store_card(store: Store) -> dict[str, Any] | None:
    """`read_card` of a dataset in a store."""
    text = store.read(CARD_JSON)
    if text is None:
        return None
    try:
        card = parse_json(text)
    except JsonError as exc:
        raise ValueError(
            f"{store.url(CARD_JSON)}: expected a reform-sim dataset card (JSON), found {exc}"
        ) from None
    return _checked_card(card, store.url(CARD_JSON))


def _check_store(store: Store, parameters: Mapping[str, Any], episodes: int) -> None:
    """`_check_folder` of a prefix in a store: empty, or holding this dataset alone."""
    _check_contents(
        store.uri,
        {name.split("/", 1)[0] for name in store.sizes()},
        _store_card(store),
        parameters,
        episodes,
        things="objects",
        instead="an empty prefix or one written by reform-sim generate",
        also_ours=(COMMITS_DIR,),
    )


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True
    return True


@contextlib.contextmanager
def _store_lock(store: Store) -> Iterator[None]:
    """Holds the lock object of a prefix in a store, refusing a second concurrent run.

    The lock is created only if there is none. One held by a run of this machine whose process
    is gone (killed) is taken over, only if it is still that run's (a conditional overwrite);
    one of another machine is refused, with what to delete if that run is gone.
    """
    mine = json.dumps(
        {
            "host": socket.gethostname(),
            "pid": os.getpid(),
            "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        }
    ).encode()
    if not store.create(LOCK_FILE, mine):
        tag = store.tag(LOCK_FILE)
        holder = _lock_holder(store) or {}
        pid = holder.get("pid")
        if not (_holder_state(holder) == "stale" and tag and store.replace(LOCK_FILE, mine, tag)):
            raise FolderRefused(
                store.uri,
                f"is being written by another reform-sim generate run "
                f"(host {holder.get('host', '?')}, process {pid or '?'}, since "
                f"{holder.get('started', '?')}); wait for it to finish or use another prefix; "
                f"if that run is gone, delete {store.url(LOCK_FILE)}"
            )
    try:
        yield
    except BaseException:
        with contextlib.suppress(StoreError):  # a store that stopped answering is already said
            _release_store_lock(store, mine)
        raise
    _release_store_lock(store, mine)


def _release_store_lock(store: Store, mine: bytes) -> None:
    if store.read(LOCK_FILE) == mine:
        store.delete(LOCK_FILE)


def _lock_holder(store: Store) -> dict[str, Any] | None:
    """What the lock object of a prefix says of its run (host, pid, started); None without
    one, empty when it says nothing readable."""
    text = store.read(LOCK_FILE)
    if text is None:
        return None
    try:
        holder = parse_json(text or b"{}")
    except JsonError:
        return {}
    return holder if isinstance(holder, dict) else {}


def _holder_state(holder: Mapping[str, Any]) -> str:
    """``"stale"``: a run of this machine whose process is gone; ``"live"``: one whose process
    runs; ``"elsewhere"``: a run of another machine (or one the lock does not name), whose
    process this machine cannot ask about."""
    pid = holder.get("pid")
    if holder.get("host") != socket.gethostname() or not isinstance(pid, int):
        return "elsewhere"
    return "live" if _alive(pid) else "stale"


def _store_leftovers(store: Store) -> list[str]:
    """`leftovers` of a prefix in a store: the unfinished multipart uploads below it (a writer
    killed while it sent a large object in parts; none while a run of this machine holds the
    lock, they may be its own) and a lock no run holds."""
    holder = _lock_holder(store)
    state = None if holder is None else _holder_state(holder)
    lines = []
    if state != "live":
        now = datetime.datetime.now(datetime.UTC)
        for upload in store.uploads():
            size = sizing.format_size(upload.size)
            age = sizing.format_duration(max(0.0, (now - upload.written).total_seconds()))
            lines.append(
                f"{store.url(upload.relative)}: an unfinished upload ({size} sent, last written "
                f"{age} ago; upload ID {upload.upload_id}) of a run that did not finish; the next "
                "generate run in this prefix removes it"
            )
    if holder is not None and state != "live":
        since = holder.get("started", "?")
        if state == "stale":
            lines.append(
                f"{store.url(LOCK_FILE)}: a lock left by a run that did not finish (process "
                f"{holder['pid']} of this machine, gone, since {since}); the next generate run "
                "in this prefix takes it over"
            )
        else:
            lines.append(
                f"{store.url(LOCK_FILE)}: a lock of process {holder.get('pid', '?')} of host "
                f"{holder.get('host', '?')} (since {since}), which this machine cannot ask about; "
                "delete it if no run there writes this prefix"
            )
    return lines


def _remove_unfinished_uploads(store: Store) -> None:
    """Aborts what killed runs left unfinished below a prefix whose lock this run holds (no
    other run writes there); a clean-up never fails a run."""
    with contextlib.suppress(OSError, StoreError):
        store.abort(*store.uploads())


def _committed_shards(
    store: Store, spec: GenerationSpec, episodes: int
) -> dict[int, tuple[ShardSummary, dict[str, Any]]]:
    """The shards already done in a store: listed by its card with their size and sha256 (a
    finished dataset being extended) or committed by a run, each still there with that size
    and of its episode. Any other shard object is written again."""
    folder = StoreFolder(store)
    entries: dict[int, Mapping[str, Any]] = {}
    card = _store_card(store)
    for entry in (card or {}).get("shards", []):
        if isinstance(entry, dict) and "sha256" in entry:
            entries[int(entry["episode"])] = entry
    entries.update(folder.commits())
    candidates = {}
    for k, entry in entries.items():
        expected = _summary(spec, k, 0, 0, 0, {})
        path = f"{DATA_DIR}/{expected.path}"
        if k >= episodes or entry.get("path") != path:
            continue
        summary = ShardSummary.from_json({**entry, "path": expected.path})
        if (summary.seed, summary.sequence) != (expected.seed, expected.sequence):
            continue
        if path not in folder.objects:
            continue
        candidates[k] = (summary, {"bytes": entry["bytes"], "sha256": entry["sha256"]})
    return _verified_objects(store, candidates)


def _verified_objects(
    store: Store, candidates: Mapping[int, tuple[ShardSummary, dict[str, Any]]]
) -> dict[int, tuple[ShardSummary, dict[str, Any]]]:
    """The shards of ``candidates`` whose objects are as they were written: each read and its
    size and sha256 checked against those recorded then (a few fetched at once). A damaged one
    is named on stderr and left out (made again)."""
    done = {}
    order = sorted(candidates)
    for start in range(0, len(order), VERIFY_BATCH):
        batch = order[start : start + VERIFY_BATCH]
        paths = {k: f"{DATA_DIR}/{candidates[k][0].path}" for k in batch}
        contents = store.read_many(list(paths.values()))
        for k in batch:
            content = contents[paths[k]]
            if content is None:
                continue
            found = {"bytes": len(content), "sha256": hashlib.sha256(content).hexdigest()}
            damage = _damage(store.url(paths[k]), found, candidates[k][1])
            if damage:
                print(damage, file=sys.stderr, flush=True)
                continue
            done[k] = candidates[k]
    return done


# ------------------------------------------------------------------------------------------
# A folder on this machine: lock, finished shards


@contextlib.contextmanager
def _folder_lock(out_dir: Path) -> Iterator[None]:
    """Holds an exclusive lock on the folder (POSIX), refusing a second concurrent run.

    The lock file is removed when the run ends: its holder deletes it before letting go, and a
    run that locked a file deleted meanwhile (by a run that just ended) locks the new one, so two
    runs never hold two files.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: no lock
        yield
        return
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / LOCK_FILE
    while True:
        handle = open(path, "a+", encoding="utf-8")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.close()
            raise FolderRefused(
                out_dir,
                "is being written by another reform-sim generate run; wait "
                "for it to finish or use another folder"
            ) from None
        with contextlib.suppress(FileNotFoundError):
            if os.path.samestat(os.fstat(handle.fileno()), os.stat(path)):
                break
        handle.close()  # deleted by a run that ended meanwhile: lock the new file
    with handle:
        try:
            yield
        finally:
            path.unlink(missing_ok=True)
            fcntl.flock(handle, fcntl.LOCK_UN)


def leftovers(out_dir: str | os.PathLike[str]) -> list[str]:
    """What killed runs left in a generated folder (never removed here), one line each: their
    temporary files and folders (in the folder and every folder below it), and a lock no run
    holds. A temporary being written now by a live process, and a lock a run holds, are not
    leftovers and are not listed.

    In a store (``out_dir`` a URI), what killed runs leave is unfinished multipart uploads
    and a lock no run holds (`_store_leftovers`).

    Args:
        out_dir: the folder (on this machine), or its URI in a store.
    """
    from reform.atomic import find_temporaries

    if is_uri(out_dir):
        return _store_leftovers(open_store(str(out_dir)))
    root = Path(out_dir)
    lines = []
    for folder, names, _ in os.walk(root):
        named = {t.path.name: t for t in find_temporaries(folder)}
        for name in sorted(names):  # temporary folders are not walked
            if name in named or (name.startswith(".") and name.endswith(".tmp")):
                names.remove(name)
        for name in sorted(os.listdir(folder)):
            path = Path(folder, name)
            temporary = named.get(name)
            if temporary is None and not (name.startswith(".") and name.endswith(".tmp")):
                continue
            size = sizing.format_size(_tree_bytes(path))
            if temporary is None:
                lines.append(
                    f"{path}: a leftover temporary file ({size}) of a run that did not finish; "
                    "the next generate run in this folder removes it"
                )
            elif temporary.state == "stale":
                lines.append(
                    f"{path}: a leftover temporary file ({size}) of a killed run (process "
                    f"{temporary.pid} of this machine, gone); the next write into "
                    f"{path.parent} removes it"
                )
            elif temporary.state == "elsewhere":
                lines.append(
                    f"{path}: a temporary file ({size}) of process {temporary.pid} of another "
                    "machine or container; remove it if no run there writes this folder"
                )
    lock = root / LOCK_FILE
    if lock.exists() and not _lock_held(lock):
        lines.append(
            f"{lock}: a lock left by a run that did not finish (no run holds it); the next "
            "generate run in this folder takes it over"
        )
    return lines


def _tree_bytes(path: Path) -> int:
    if not path.is_dir():
        return path.lstat().st_size
    return sum(p.lstat().st_size for p in path.rglob("*") if not p.is_dir())


def _lock_held(path: Path) -> bool:
    """Whether a live run holds the lock file ``path`` (`_folder_lock`); when unsure: yes."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: no lock to ask
        return True
    try:
        with open(path, encoding="utf-8") as handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except BlockingIOError:
                return True
            fcntl.flock(handle, fcntl.LOCK_UN)
            return False
    except OSError:
        return True


def _remove_stale_temporaries(out_dir: Path) -> None:
    """Temporary files of a killed run (``.part.parquet.*.tmp`` and the like)."""
    for pattern in (
        f"{DATA_DIR}/scenario=*/episode=*/.*.tmp",
        "scenario=*/episode=*/.*.tmp",
        f"{RECORDINGS_DIR}/.*.tmp",
        f"{COMMITS_DIR}/.*.tmp",
        ".*.tmp",
    ):
        for path in out_dir.glob(pattern):
            if path.is_dir():
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)


def _recorded_files(folder: _Folder) -> dict[int, Mapping[str, Any]]:
    """The size and sha256 recorded for each shard when it was written: listed by the card (a
    finished dataset, or the shards a resumed run kept), or by the shard's commit file (written
    before the shard was renamed into place; the newer of the two)."""
    entries: dict[int, Mapping[str, Any]] = {}
    try:
        card = read_card(folder.out)
    except ValueError:
        card = None
    commits = folder.out / COMMITS_DIR
    found = [e for e in (card or {}).get("shards", []) if isinstance(e, dict)]
    for path in sorted(commits.glob("episode=*.json")) if commits.is_dir() else []:
        try:
            entry = parse_json(path.read_bytes())
        except (OSError, JsonError):
            continue  # an unreadable commit records nothing: its shard is made again
        found.append(entry if isinstance(entry, dict) else {})
    for entry in found:
        if isinstance(entry.get("episode"), int) and "sha256" in entry and "bytes" in entry:
            entries[entry["episode"]] = entry
    return entries


def _damage(where: str, found: Mapping[str, Any], recorded: Mapping[str, Any]) -> str | None:
    """What differs between a shard (its ``bytes`` and ``sha256``) and its record; None when
    nothing does."""
    if found["bytes"] != recorded.get("bytes"):
        what = f"{found['bytes']} bytes, not the {recorded.get('bytes')}"
    elif found["sha256"] != recorded.get("sha256"):
        what = f"sha256 {found['sha256']}, not the {recorded.get('sha256')}"
    else:
        return None
    return (
        f"reform-sim generate: {where} is damaged ({what} recorded when it was written); "
        "it is made again"
    )


def _verified_shards(
    folder: _Folder, spec: GenerationSpec, episodes: Sequence[int]
) -> dict[int, dict[str, Any]]:
    """The finished shards of ``episodes`` that are as they were written: each one's size and
    sha256 against those recorded then (`_recorded_files`). A damaged one is named on stderr and
    left out (made again), and so is one with no record (written by an older reform-sim).

    Returns:
        episode -> the shard's ``bytes`` and ``sha256``.
    """
    recorded = _recorded_files(folder)
    kept: dict[int, dict[str, Any]] = {}
    unrecorded: list[Path] = []
    for k in episodes:
        path = folder.shard(spec.scenario, k)
        entry = recorded.get(k)
        listed = folder.listed(_summary(spec, k, 0, 0, 0, {}))
        if entry is None or entry.get("path") != listed:
            unrecorded.append(path)
            continue
        found = _file_entry(path)
        damage = _damage(str(path), found, entry)
        if damage:
            print(damage, file=sys.stderr, flush=True)
            continue
        kept[k] = found
    if unrecorded:
        print(
            f"reform-sim generate: {folder.out}: {len(unrecorded)} shard(s) with no checksum "
            f"record to check them against (the first: {unrecorded[0]}; the card does not list "
            f"it and its file under {COMMITS_DIR}/ is missing, unreadable or of another shard, "
            "or an older reform-sim wrote it): they are made again",
            file=sys.stderr,
            flush=True,
        )
    return kept


def _written_files(
    folder: _Folder, summaries: Sequence[ShardSummary], kept: Mapping[int, Mapping[str, Any]]
) -> dict[str, Mapping[str, Any]]:
    """Each shard's size and sha256 for the final card: those checked on resume (``kept``), and
    those recorded as the others were written (their commits); never read again from the files,
    so that a shard altered since is never vouched for."""
    records = _recorded_files(folder)
    files = {}
    for summary in summaries:
        entry = kept.get(summary.episode) or records.get(summary.episode)
        if entry is None or (
            summary.episode not in kept and entry.get("path") != folder.listed(summary)
        ):
            raise RuntimeError(  # pragma: no cover - every shard written is committed first
                f"{folder.root / summary.path}: no checksum recorded when it was written"
            )
        files[summary.path] = {"bytes": entry["bytes"], "sha256": entry["sha256"]}
    return files


def _finished(folder: _Folder, spec: GenerationSpec, episode: int, save_recordings: bool) -> bool:
    if not folder.shard(spec.scenario, episode).is_file():
        return False
    return not save_recordings or _recording_path(folder.out, episode).is_file()


def _existing_shards(
    folder: _Folder, spec: GenerationSpec, episodes: int
) -> dict[int, ShardSummary]:
    """The summaries of the shards already in the folder, each checked to be its episode's.

    A shard copied or moved to another episode's place would otherwise be taken for that
    episode, and the folder called complete while reading it fails. Nothing is changed when one
    is wrong: the error lists the files, for the user to delete (to make them again) or put back.

    Raises:
        ValueError: a shard is not the one its place says (other episode, seed, sequence or
            parameters), or not a shard of reform-sim generate; naming each such file.
    """

    shards: dict[int, ShardSummary] = {}
    problems: list[DataFormatError] = []
    for k in range(episodes):
        path = folder.shard(spec.scenario, k)
        if not path.is_file():
            continue
        try:
            shards[k] = _checked_shard(path, spec, k)
        except DataFormatError as exc:
            problems.append(exc)
    if problems:
        shown = "; ".join(str(p) for p in problems[:SHOWN_PROBLEMS])
        more = len(problems) - SHOWN_PROBLEMS
        raise FolderRefused(
            folder.out,
            f": {len(problems)} of the {len(problems) + len(shards)} shards "
            f"already there {'is' if len(problems) == 1 else 'are'} not the episode "
            f"{'its place says' if len(problems) == 1 else 'their places say'}: {shown}"
            + (f"; and {more} more" if more > 0 else "")
            + ". Nothing was changed: delete the file(s) named to have them made again, or "
            "put the right ones back"
        ) from problems[0]
    return shards


def _checked_shard(path: Path, spec: GenerationSpec, episode: int) -> ShardSummary:
    """The summary a finished shard carries, after checking that it is episode ``episode`` of
    this dataset: its metadata's episode, seed, sequence and parameters, and its ``sequence``
    column. Only the footer is read (metadata and row-group statistics), plus the sequence
    column when the file has no statistics; never the frames.

    Raises:
        DataFormatError: naming the file, what was expected and what was found.
    """

    try:
        handle = pq.ParquetFile(path)
        raw = (handle.schema_arrow.metadata or {})[METADATA_KEY]
        metadata = json.loads(raw)["metadata"]
        summary = ShardSummary.from_json(metadata["episode"])
        parameters = metadata["parameters"]
    except Exception as exc:
        raise DataFormatError(
            path,
            None,
            "schema metadata",
            "a shard written by reform-sim generate (metadata.episode)",
            f"{type(exc).__name__}: {exc}",
        ) from exc
    expected = _summary(spec, episode, 0, 0, 0, {})
    if (summary.episode, summary.seed, summary.sequence) != (
        expected.episode,
        expected.seed,
        expected.sequence,
    ):
        raise DataFormatError(
            path,
            None,
            "metadata.episode",
            f"the shard of {_episode_text(expected)}",
            f"the shard of {_episode_text(summary)}",
        )
    wanted = spec.parameters()
    differing = sorted(
        k for k in set(parameters) | set(wanted) if parameters.get(k) != wanted.get(k)
    )
    if differing:
        details = ", ".join(
            f"{k} {json.dumps(parameters.get(k))} (expected {json.dumps(wanted.get(k))})"
            for k in differing
        )
        raise DataFormatError(
            path,
            None,
            "metadata.parameters",
            f"the parameters of this dataset's {CARD_JSON}",
            f"a shard of another dataset: {details}",
        )
    found = _sequences(handle)
    if found != {expected.sequence}:
        raise DataFormatError(
            path,
            None,
            "sequence",
            f"frames of sequence {expected.sequence!r} only ({_episode_text(expected)})",
            "no sequence column" if found is None else f"sequence(s) {sorted(found)}",
        )
    return summary


def _episode_text(summary: ShardSummary) -> str:
    return f"episode {summary.episode} (sequence {summary.sequence!r}, seed {summary.seed})"


def _sequences(handle: Any) -> set[str] | None:
    """The values of a Parquet file's ``sequence`` column (``None`` without one): from the
    statistics of every row group when written, else from the column's values."""
    metadata = handle.metadata
    paths = [metadata.schema.column(i).path for i in range(metadata.num_columns)]
    if "sequence" not in paths:
        return None
    column = paths.index("sequence")
    values: set[str] = set()
    for group in range(metadata.num_row_groups):
        stats = metadata.row_group(group).column(column).statistics
        if stats is None or not stats.has_min_max:
            table = handle.read(columns=["sequence"])
            return {str(v) for v in table.column("sequence").unique().to_pylist()}
        values.update((str(stats.min), str(stats.max)))
    return values


# ------------------------------------------------------------------------------------------
# The card


def _card(
    spec: GenerationSpec,
    episodes: int,
    shards: Sequence[ShardSummary],
    *,
    complete: bool,
    resolved_options: Mapping[str, Any] | None,
    files: Mapping[str, Mapping[str, Any]] | None = None,
    data_dir: str = DATA_DIR,
) -> dict[str, Any]:
    """The card; ``files`` (shard path -> ``bytes`` and ``sha256``) are listed with each shard,
    so that a reader can tell a missing, truncated or altered shard (the final card has them).
    Shards are listed by their path in the folder (under ``data_dir``)."""
    files = files or {}
    folder = _Folder(Path(), data_dir)
    sizes: Counter[int] = Counter()
    for shard in shards:
        sizes.update(shard.group_sizes)
    return {
        "card_version": CARD_VERSION,
        "kind": "reform-sim synthetic dataset",
        "complete": complete,
        "parameters": spec.parameters(),
        "scenario_options_resolved": resolved_options,
        "episodes": episodes,
        "layout": f"{data_dir + '/' if data_dir else ''}scenario={spec.scenario}/episode=<k>/"
        f"{SHARD_FILE}, sequence '{spec.scenario}-<k>'",
        "command": _command(spec, episodes),
        "totals": {
            "shards": len(shards),
            "frames": sum(s.frames for s in shards),
            "annotated_frames": sum(s.annotated_frames for s in shards),
            "rows": sum(s.rows for s in shards),
            "simulated_seconds": sum(s.duration for s in shards),
            "group_sizes": {str(k): v for k, v in sorted(sizes.items())},
            "group_events": _event_totals(shards),
        },
        "shards": [
            {**s.to_json(), "path": folder.listed(s), **files.get(s.path, {})}
            for s in sorted(shards, key=lambda s: s.episode)
        ],
    }


def _event_totals(shards: Sequence[ShardSummary]) -> dict[str, int] | None:
    """Ground-truth group events per kind over the shards; None when a shard does not say
    (written before the events were stored)."""
    if any(shard.group_events is None for shard in shards):
        return None
    totals = dict.fromkeys(EVENT_KINDS, 0)
    for shard in shards:
        for kind, count in shard.group_events.items():  # type: ignore[union-attr]
            totals[kind] = totals.get(kind, 0) + count
    return totals


def _file_entry(path: Path) -> dict[str, Any]:
    """A file's size and sha256, as the card and the commits record them."""
    digest = hashlib.sha256()
    size = 0
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
            size += len(block)
    return {"bytes": size, "sha256": digest.hexdigest()}


def _command(spec: GenerationSpec, episodes: int) -> str:
    words = [
        "reform-sim",
        "generate",
        "--scenario",
        spec.scenario,
        "--episodes",
        str(episodes),
        "--seed",
        str(spec.seed),
        "--out",
        "DIR",
    ]
    for key, value in spec.options.items():
        words += ["--set", f"{key}={json.dumps(value)}"]
    if spec.duration is not None:
        words += ["--duration", f"{spec.duration:g}"]
    words += ["--rate", f"{spec.rate:g}"]
    words += ["--view", spec.view]
    if spec.sensor is not None:
        from sim.sensor import Sensor

        default = Sensor()
        for f in dataclasses.fields(spec.sensor):
            value = getattr(spec.sensor, f.name)
            if value != getattr(default, f.name):
                flag = "--" + f.name.replace("_", "-")
                if isinstance(value, bool):
                    words.append(flag if value else "--no-" + f.name.replace("_", "-"))
                else:
                    words += [flag, f"{value:g}"]
    if spec.annotation == RANDOM_ANNOTATION:
        words += ["--annotation", RANDOM_ANNOTATION]
    elif spec.annotation is not None:
        default = AnnotationModel()
        for f in dataclasses.fields(spec.annotation):
            value = getattr(spec.annotation, f.name)
            if value != getattr(default, f.name):
                text = value if isinstance(value, str) else f"{value:g}"
                words += ["--annotation", f"{f.name}={text}"]
    return shlex.join(words)


def _annotation_text(annotation: Any) -> str:
    """The card's line on the annotation model (`reform.annotation`)."""
    if annotation is None:
        return "none: the frames as simulated"
    if annotation == RANDOM_ANNOTATION:
        return (
            "randomised: one model per episode drawn from `reform.annotation.ANNOTATION_RANGES` "
            f"(listed in {CARD_JSON}; each shard's metadata holds its own)"
        )
    return f"`{json.dumps(annotation, sort_keys=True)}` (`reform.annotation.AnnotationModel`)"


def _size_category(rows: int) -> str:
    """The Hugging Face size category of a dataset of ``rows`` rows."""
    for bound, name in SIZE_CATEGORIES:
        if rows < bound:
            return name
    return "n>1B"


def _front_matter(card: Mapping[str, Any]) -> list[str]:
    """The Hugging Face dataset-card metadata (YAML): license, task, tags, size, and the
    ``configs`` that point the hub at the shards. Strings are JSON, which YAML reads as is."""
    p = card["parameters"]
    data = str(card["layout"]).split("scenario=", 1)[0]
    q = json.dumps
    return [
        "---",
        f"license: {CARD_LICENSE}",
        f"pretty_name: {q('reform-sim synthetic dataset: ' + p['scenario'])}",
        "task_categories:",
        "- robotics",
        "tags:",
        *(f"- {t}" for t in ("f-formation", "social-robotics", "group-detection", "synthetic")),
        *(f"- {t}" for t in ("simulation", "mujoco", "reform-sim")),
        "size_categories:",
        f"- {q(_size_category(int(card['totals']['rows'])))}",
        "configs:",
        "- config_name: default",
        "  data_files:",
        "  - split: train",
        f"    path: {q(data + 'scenario=*/episode=*/*.parquet')}",
        "---",
        "",
    ]


def _markdown(card: Mapping[str, Any]) -> str:
    p = card["parameters"]
    totals = card["totals"]
    data = str(card["layout"]).split("scenario=", 1)[0]
    lines = [
        *_front_matter(card),
        f"# Synthetic dataset: {p['scenario']}",
        "",
        f"Generated by {p['package_version']} ({card['kind']}); "
        + ("complete." if card["complete"] else "**incomplete**: resume with the command below."),
        "",
        "Reproduce (byte for byte) or resume:",
        "",
        "```",
        card["command"],
        "```",
        "",
        "Load it:",
        "",
        "```python",
        "from reform.datasets import read_parquet",
        "dataset = read_parquet('DIR')"
        if card["complete"]
        else "dataset = read_parquet('DIR', allow_incomplete=True)  # the episodes written so far",
        "```",
        "",
        "Other tools read the shards (one row per person and frame, columns "
        "`reform.datasets.COLUMNS`, plus the hive columns `scenario` and `episode`):",
        "",
        "```python",
        "import pandas",
        f"table = pandas.read_parquet('DIR/{data}')",
        "import duckdb",
        f"duckdb.sql(\"SELECT * FROM read_parquet('DIR/{data}**/*.parquet', "
        'hive_partitioning = true)")',
        "```",
        "",
        "## Parameters",
        "",
        "| parameter | value |",
        "| --- | --- |",
        f"| scenario | `{p['scenario']}` |",
        f"| scenario options (given) | `{json.dumps(p['options'], sort_keys=True)}` |",
        f"| master seed | {p['seed']} |",
        f"| episode seeds | {p['seed_rule']} (listed per shard in {CARD_JSON}) |",
        f"| view | {p['view']} |",
        f"| sensor | {_sensor_text(p['sensor'])} |",
        f"| rate | {p['rate_hz']:g} Hz |",
        f"| episode duration | {_duration_text(p['duration_s'])} |",
        f"| annotation | {_annotation_text(p.get('annotation'))} |",
        f"| package version | {p['package_version']} |",
        f"| Parquet format version | {p['format_version']} |",
        f"| episodes | {card['episodes']} |",
        f"| layout | `{card['layout']}` |",
        "",
    ]
    resolved = card.get("scenario_options_resolved")
    if resolved:
        lines += ["Scenario options in force (defaults filled in):", "", "| option | value |"]
        lines += ["| --- | --- |"]
        lines += [f"| {k} | `{json.dumps(v)}` |" for k, v in resolved.items()]
        lines.append("")
    lines += [
        "## Contents",
        "",
        "| | count |",
        "| --- | ---: |",
        f"| shards written | {totals['shards']} of {card['episodes']} |",
        f"| frames | {totals['frames']:,} |",
        f"| annotated frames | {totals['annotated_frames']:,} |",
        f"| person entries (rows) | {totals['rows']:,} |",
        f"| simulated time | {totals['simulated_seconds']:,.1f} s |",
        "",
        "Group sizes over the annotated frames (everyone counted: a person alone is a group of "
        "size 1, the robot counts as a member):",
        "",
        "| size | groups |",
        "| ---: | ---: |",
    ]
    lines += [f"| {k} | {v:,} |" for k, v in totals["group_sizes"].items()]
    lines.append("")
    lines += _events_markdown(totals.get("group_events"))
    return "\n".join(lines)


def _events_markdown(events: Mapping[str, int] | None) -> list[str]:
    """The card's section on the ground-truth group events."""
    lines = ["## Group events", ""]
    if events is None:
        return [
            *lines,
            "Not counted: some shards were written before their group events were stored "
            "(`reform.datasets.dataset_group_events` derives them from the frames).",
            "",
        ]
    lines += [
        "Ground-truth group events over the annotated frames (`reform.events`: F-formations "
        "of two or more, between consecutive annotated frames of an episode). Each shard "
        f"stores its own in its metadata (`{GROUP_EVENTS_KEY}`); "
        "`reform.datasets.dataset_group_events(read_parquet('DIR'))` gives them all:",
        "",
        "| kind | events |",
        "| --- | ---: |",
    ]
    lines += [f"| {kind} | {count:,} |" for kind, count in events.items()]
    lines += [f"| all | {sum(events.values()):,} |", ""]
    return lines


def _duration_text(value: float | None) -> str:
    return "each episode's natural length" if value is None else f"{value:g} s"


def _sensor_text(sensor: Mapping[str, Any] | None) -> str:
    if sensor is None:
        return "none (ground truth)"
    return ", ".join(f"{k}={v}" for k, v in sensor.items())


def _write_cards(out_dir: Path, card: Mapping[str, Any]) -> None:
    with atomic_open(out_dir / CARD_JSON, "w", encoding="utf-8") as handle:
        json.dump(card, handle, indent=2, allow_nan=False)
        handle.write("\n")
    with atomic_open(out_dir / CARD_MARKDOWN, "w", encoding="utf-8") as handle:
        handle.write(_markdown(card))


# ------------------------------------------------------------------------------------------
# Checks before any work


def _check_scenario(spec: GenerationSpec) -> tuple[dict[str, Any], Any]:
    """Makes episode 0's scenario and its scene: an unknown name (the known ones are listed),
    unknown or impossible options, a robot view without a robot fail here, before any work.

    Returns:
        The scenario's options with its defaults filled in, and episode 0's made scenario.
    """

    scenarios.describe(spec.scenario)  # an unknown name: the registry's one message
    made = prepare(spec.scenario, seed=episode_seed(spec.seed, 0), options=spec.options)
    scene_spec(made.stage, name=made.name)
    length = made.duration if spec.duration is None else spec.duration
    if isinstance(spec.annotation, AnnotationModel) and (
        spec.annotation.min_group_seconds >= length
    ):
        raise ValueError(
            f"annotation min_group_seconds must be shorter than the episodes ({length:g} s), got "
            f"{spec.annotation.min_group_seconds:g}: no group would ever be called"
        )
    if spec.view == "robot" and made.stage.robot is None:
        raise ValueError(
            f"view='robot' needs a robot, and {scenarios.without_robot(spec.scenario)}"
        )
    return _json_value("scenario options", dict(made.options)), made


def _check_size(
    spec: GenerationSpec,
    made: Any,
    *,
    episodes: int,
    out_dir: Path | None,
    workers: int,
    save_recordings: bool,
    max_memory: int | None,
) -> sizing.Estimate:
    """Refuses, before any work, a dataset that cannot fit this machine (`sim.sizing.check`):
    its episodes sized like episode 0 (``made``), ``workers`` of them held at once; the disk
    needed is for the episodes whose shards are not there yet. Returns episode 0's estimate,
    which `_say_estimate` scales to the episodes left once they are known."""

    one = estimate_episode(
        made,
        duration=spec.duration,
        rate=spec.rate,
        view=spec.view,
        recording=save_recordings,
        recording_model=save_recordings,  # `_record` draws the scene's model
    )
    estimate = sizing.dataset_estimate(
        one,
        episodes=episodes,
        workers=workers,
        arrays=spec.view == "truth" and not save_recordings,
    )
    there = 0
    if out_dir is not None:
        folder = _Folder(out_dir, folder_layout(out_dir)).root / f"scenario={spec.scenario}"
        there = sum(1 for _ in folder.glob(f"episode=*/{SHARD_FILE}")) if folder.is_dir() else 0
    missing = max(0, episodes - there)
    sizing.check(
        estimate,
        what=f"{sizing.count(episodes)} episodes of {spec.scenario}",
        shrink="fewer {episodes}, a shorter {duration} or a lower {rate}",
        memory_limit=max_memory,
        alternative="fewer workers ({n_jobs})" if workers > 1 else "",
        out=out_dir,
        out_option="out_dir",
        disk_needed=estimate.disk * missing / episodes,
    )
    return one


def _check_size_unplanned(spec: GenerationSpec, **sizes: Any) -> None:
    """`_check_size` before episode 0 is planned, for a length given as the scenario's option
    ``duration``: `_check_scenario` plans the whole of it (a day's episode takes a minute),
    while the size needs only the stage's people and robot, which the length does not change;
    they are taken from episode 0 made at the scenario's own length. Options this cannot make
    are left for `_check_scenario` to refuse, in its words; `_check_size` runs again on the
    planned episode."""
    length = spec.options.get("duration") if spec.duration is None else None
    if length is None:  # the scenario's own length, or one applied after planning: quick
        return
    try:
        sized = dataclasses.replace(spec, duration=length)
        options = {k: v for k, v in spec.options.items() if k != "duration"}
        stage = prepare(spec.scenario, seed=episode_seed(spec.seed, 0), options=options)
    except (TypeError, ValueError):
        return
    _check_size(sized, stage, **sizes)


def _say_estimate(
    spec: GenerationSpec,
    one: sizing.Estimate,
    *,
    todo: int,
    episodes: int,
    workers: int,
    save_recordings: bool,
) -> None:
    """States on stderr, once, what the ``todo`` episodes left of ``episodes`` will take on
    ``workers`` processes (their start included: `sim.sizing.pool_start`); nothing when none
    is left, the run having nothing to do."""
    if not todo:
        return
    left = sizing.dataset_estimate(
        one, episodes=todo, workers=workers, arrays=spec.view == "truth" and not save_recordings
    )
    what = f"{sizing.count(todo)} episode{'s' * (todo != 1)} of {spec.scenario}"
    if todo < episodes:
        what += f" ({sizing.count(episodes - todo)} of {sizing.count(episodes)} already there)"
    print(sizing.describe(left, what), file=sys.stderr, flush=True)


def _batches(episodes: Sequence[int], workers: int) -> list[list[int]]:
    """Contiguous batches: about ``TASKS_PER_WORKER`` per worker, at most
    ``MAX_EPISODES_PER_TASK`` episodes each."""
    if not episodes:
        return []
    tasks = max(1, min(len(episodes), workers * TASKS_PER_WORKER))
    size = max(1, min(MAX_EPISODES_PER_TASK, math.ceil(len(episodes) / tasks)))
    return [list(episodes[i : i + size]) for i in range(0, len(episodes), size)]


def _batch_text(scenario: str, batch: Sequence[int]) -> str:
    """A batch in a message: ``"episodes 4-7 of mingle"`` (a worker that died held it)."""
    span = f" {batch[0]}" if len(batch) == 1 else f"s {batch[0]}-{batch[-1]}"
    return f"episode{span} of {scenario}"


# ------------------------------------------------------------------------------------------
# Backends


def _plan(
    executor: Executor, todo: Sequence[int], n_jobs: int | None
) -> tuple[int, list[list[int]]]:
    """The workers that run the episodes ``todo`` (every CPU of a Ray cluster; else no more
    local processes than episodes: the report says how many ran), and their batches."""
    if executor.remote:
        workers = executor.workers
    else:
        workers = max(1, min(n_jobs or cpu_count(), len(todo)))
    return workers, _batches(todo, workers)


def _written(
    results: Iterable[tuple[int, list[tuple[ShardSummary, bytes, bytes | None]]]], folder: _Folder
) -> Iterator[list[ShardSummary]]:
    """Writes the shards (and recordings) that remote workers send back as bytes into
    ``folder``, each atomically, as they come (``results``: `Executor.imap_unordered`'s)."""
    for _, batch in results:
        for summary, shard, recording in batch:
            if recording is not None:
                with atomic_path(_recording_path(folder.out, summary.episode)) as tmp:
                    tmp.write_bytes(recording)
            with atomic_path(folder.root / summary.path) as tmp:
                tmp.write_bytes(shard)
                files = {"bytes": len(shard), "sha256": hashlib.sha256(shard).hexdigest()}
                _write_commit(folder, summary, files)
        yield [summary for summary, _, _ in batch]


# ------------------------------------------------------------------------------------------
# The entry point


def generate_dataset(
    scenario: str,
    *,
    episodes: int,
    seed: int,
    out_dir: str | os.PathLike[str],
    options: Mapping[str, Any] | None = None,
    view: str = "truth",
    sensor: Any = None,
    rate: float = DEFAULT_RATE_HZ,
    duration: float | None = None,
    annotation: Any = None,
    backend: str = "local",
    address: str | None = None,
    n_jobs: int | None = None,
    save_recordings: bool = False,
    progress: bool = True,
    max_memory: int | None = None,
) -> GenerationReport:
    """Generates (or resumes, or extends) a synthetic dataset of ``episodes`` episodes.

    Args:
        scenario: a registered scenario name (``scenarios.names()``).
        episodes: number of episodes (shards), >= 1.
        seed: master seed, >= 0; episode ``k`` gets `episode_seed`\\ ``(seed, k)``.
        out_dir: the dataset folder: new, empty, or holding this same dataset (resume/extend);
            a path, or a store's URI (``s3://bucket/prefix``, any fsspec filesystem;
            credentials from the environment, `reform.datasets.store`).
        options: scenario option overrides (JSON values), as for ``scenarios.make``.
        view: ``"truth"`` or ``"robot"`` (observed by the robot's head sensor).
        sensor: the robot view's sensor model: a ``sim.Sensor`` or a mapping of its fields;
            ``None`` for its defaults (robot view) or no sensor (truth view).
        rate: output (annotation) rate, Hz (2 Hz, SALSA's, by default).
        duration: episode length, seconds; ``None`` for each episode's natural length.
        annotation: how the annotation records each episode (`reform.annotation`): an
            `AnnotationModel` or its settings, ``"random"`` (one model drawn per episode from
            `reform.annotation.ANNOTATION_RANGES`, each recorded in its shard), or ``None``.
        backend: ``"local"`` (processes on this machine) or ``"ray"`` (remote tasks).
        address: the Ray cluster's address (``"auto"``, ``"ray://host:10001"``, ``host:6379``);
            ``None`` joins the Ray instance already running in this process, else starts one.
            Probed before any work (`sim.executor.check_address`).
        n_jobs: local worker processes (default: every core); ignored by Ray.
        save_recordings: also write one Rerun ``.rrd`` per episode under ``recordings/``.
        progress: show a progress bar on stderr.
        max_memory: bytes of memory the run may take (its workers each hold one episode
            whole); None for what this machine has available.

    Returns:
        A `GenerationReport`.

    Raises:
        ValueError: bad parameters, an unknown scenario (the known ones are listed), impossible
            scenario options, or an ``out_dir`` holding something else: before any work.
        reform.datasets.store.StoreError: (a ValueError) a store that cannot be used: no
            credentials, unreachable, no such bucket; before any work.
        sim.sizing.RequestTooLarge: (a ValueError) a dataset whose memory, disk or time cannot
            fit this machine (`sim.sizing.check`), before any work.
        sim.executor.ClusterError: an ``address`` where no Ray cluster answers (one line, within
            seconds, before any work), or a batch whose worker was lost more often than retried.
        ImportError: ``backend="ray"`` without Ray installed.
    """
    started = time.perf_counter()
    episodes = _check_int("episodes", episodes, minimum=1)
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if address is not None and backend != "ray":
        raise ValueError(f"address is for backend='ray', got address={address!r} with {backend!r}")
    if n_jobs is not None:
        n_jobs = _check_int("n_jobs", n_jobs, minimum=1)
    spec = GenerationSpec(
        scenario=scenario,
        options=dict(options or {}),
        seed=seed,
        view=view,
        sensor=sensor,
        rate=rate,
        duration=duration,
        annotation=annotation,
    )
    if max_memory is not None:
        max_memory = _check_int("max_memory", max_memory, minimum=1)
    local = backend == "local"
    environment = None
    if local and is_uri(out_dir):  # local workers write to the store with its variables as now
        environment = {k: v for k, v in os.environ.items() if k.startswith(STORE_ENVIRONMENT)}
    executor = Executor(  # a Ray address is probed here, before any work; _drain draws the bar
        backend,
        jobs=n_jobs if local else None,
        address=address,
        progress=False,
        environment=environment,
    )
    store = open_store(os.fspath(out_dir)) if is_uri(out_dir) else None
    if store is None:
        out_dir = Path(out_dir)
    sizes = dict(
        episodes=episodes,
        out_dir=out_dir if store is None else None,
        workers=(n_jobs or cpu_count()) if local else 1,
        save_recordings=save_recordings,
        max_memory=max_memory,
    )
    with _collector_spared():
        _check_size_unplanned(spec, **sizes)
        resolved, made = _check_scenario(spec)
    one = _check_size(spec, made, **sizes)
    if store is not None:
        todo, done, summaries, workers, check_seconds = _generate_store(
            store,
            spec,
            executor,
            episodes=episodes,
            resolved=resolved,
            n_jobs=n_jobs,
            save_recordings=save_recordings,
            progress=progress,
        )
        where, card_url = store.uri, store.url
    else:
        parameters = spec.parameters()
        _check_folder(out_dir, parameters, episodes)
        with _folder_lock(out_dir), executor:
            _check_folder(out_dir, parameters, episodes)  # again, now that no other run can write
            folder = _Folder(out_dir, folder_layout(out_dir))
            _remove_stale_temporaries(out_dir)
            checking = time.perf_counter()
            existing = _existing_shards(folder, spec, episodes)
            finished = [k for k in existing if _finished(folder, spec, k, save_recordings)]
            kept = _verified_shards(folder, spec, finished)  # each against its recorded sha256
            check_seconds = time.perf_counter() - checking
            done = sorted(kept)
            shards = {k: existing[k] for k in done}
            todo = [k for k in range(episodes) if k not in shards]
            _write_cards(
                out_dir,
                _card(
                    spec,
                    episodes,
                    list(shards.values()),
                    complete=False,
                    resolved_options=resolved,
                    files={shards[k].path: kept[k] for k in done},
                    data_dir=folder.data,
                ),
            )
            workers, batches = _plan(executor, todo, n_jobs)
            describe = functools.partial(_batch_text, spec.scenario)
            if progress:  # stated once, the time being an estimate a run is not refused on
                _say_estimate(
                    spec,
                    one,
                    todo=len(todo),
                    episodes=episodes,
                    workers=workers,
                    save_recordings=save_recordings,
                )
            if executor.remote:  # the shards come back as bytes, written here
                shared: tuple[Any, ...] = (spec, save_recordings)
                results = _written(
                    executor.imap_unordered(
                        _run_batch_bytes, batches, shared=shared, describe=describe
                    ),
                    folder,
                )
            else:
                # One worker runs the batches in this process: episode 0's scenario, made for
                # the checks above, is used as it is rather than made again.
                shared = (spec, folder, save_recordings, made if workers == 1 else None)
                results = (
                    b
                    for _, b in executor.imap_unordered(
                        _run_batch, batches, shared=shared, describe=describe
                    )
                )
            with contextlib.closing(results):  # stops the workers, if interrupted, while they run
                _drain(results, shards, episodes, spec.scenario, progress)
            summaries = [shards[k] for k in range(episodes)]
            card = _card(
                spec,
                episodes,
                summaries,
                complete=True,
                resolved_options=resolved,
                files=_written_files(folder, summaries, kept),
                data_dir=folder.data,
            )
            _write_cards(out_dir, card)
            shutil.rmtree(out_dir / COMMITS_DIR, ignore_errors=True)  # the card lists them now
        where, card_url = out_dir, out_dir.joinpath
    return GenerationReport(
        out_dir=where,
        spec=spec,
        episodes=episodes,
        generated=tuple(todo),
        skipped=tuple(done),
        shards=tuple(summaries),
        seconds=time.perf_counter() - started,
        backend=backend,
        n_jobs=workers,
        card=card_url(CARD_JSON),
        card_markdown=card_url(CARD_MARKDOWN),
        check_seconds=check_seconds,
    )


def _generate_store(
    store: Store,
    spec: GenerationSpec,
    executor: Executor,
    *,
    episodes: int,
    resolved: dict[str, Any],
    n_jobs: int | None,
    save_recordings: bool,
    progress: bool,
) -> tuple[list[int], list[int], list[ShardSummary], int, float]:
    """`generate_dataset` into a store: the workers write the shards and their commits.

    Returns:
        The episodes simulated, those found finished, every episode's shard, the workers, and
        the seconds spent checking the shards already there.
    """
    parameters = spec.parameters()
    _check_store(store, parameters, episodes)
    with _store_lock(store), executor:
        _check_store(store, parameters, episodes)  # again, now that no other run can write
        _remove_unfinished_uploads(store)
        checking = time.perf_counter()
        existing = _committed_shards(store, spec, episodes)
        check_seconds = time.perf_counter() - checking
        objects = store.sizes()
        done = [k for k in existing if not save_recordings or _recording_name(k) in objects]
        shards = {k: existing[k][0] for k in done}
        files = {existing[k][0].path: existing[k][1] for k in done}
        todo = [k for k in range(episodes) if k not in shards]
        _write_store_cards(
            store,
            _card(spec, episodes, list(shards.values()), complete=False, resolved_options=resolved),
        )
        # Every worker writes its shards to the store itself; only summaries come back.
        workers, batches = _plan(executor, todo, n_jobs)
        shared = (spec, store.uri, save_recordings)
        describe = functools.partial(_batch_text, spec.scenario)
        results = _collect(
            executor.imap_unordered(_run_batch_store, batches, shared=shared, describe=describe),
            files,
        )
        with contextlib.closing(results):  # stops the workers, if interrupted, while they run
            _drain(results, shards, episodes, spec.scenario, progress)
        summaries = [shards[k] for k in range(episodes)]
        card = _card(
            spec, episodes, summaries, complete=True, resolved_options=resolved, files=files
        )
        _write_store_cards(store, card)
        store.delete(*store.sizes(COMMITS_DIR))  # the card lists every shard now
    return todo, done, summaries, workers, check_seconds


def _write_store_cards(store: Store, card: Mapping[str, Any]) -> None:
    store.write(CARD_JSON, (json.dumps(card, indent=2, allow_nan=False) + "\n").encode())
    store.write(CARD_MARKDOWN, _markdown(card).encode())


def _collect(
    results: Iterable[tuple[int, list[tuple[ShardSummary, dict[str, Any]]]]],
    files: dict[str, dict[str, Any]],
) -> Iterator[list[ShardSummary]]:
    """The summaries of ``results`` (`Executor.imap_unordered`'s), their shards' sizes and
    sha256 kept in ``files``."""
    for _, batch in results:
        for summary, shard in batch:
            files[summary.path] = shard
        yield [summary for summary, _ in batch]


def _drain(
    results: Iterable[list[ShardSummary]],
    shards: dict[int, ShardSummary],
    episodes: int,
    scenario: str,
    progress: bool,
) -> None:
    with (
        tqdm(
            total=episodes,
            initial=len(shards),
            desc=f"generate {scenario}",
            unit="episode",
            file=sys.stderr,
            disable=not progress,
            dynamic_ncols=True,
        ) as bar,
        ticking(bar),
    ):
        frames = 0
        for batch in results:
            for summary in batch:
                shards[summary.episode] = summary
                frames += summary.annotated_frames
            bar.update(len(batch))
            bar.set_postfix(annotated_frames=frames, refresh=False)
