"""One way to derive seeds: ``numpy.random.SeedSequence(seed, spawn_key=key)``.

Every random stream of the project comes from a master seed given at the edge (a command's
``--seed``, a study's ``seed=``) and a *spawn key* saying which use it serves, so that two uses
never share draws and adding a use never reshuffles another. The keys have three layouts:

- **a study's uses**: ``(role, *keys)``, a `Role` first (the stress grid's test episodes,
  the bootstrap of one axis, the demo's tracker noise of one training scenario ...), then the
  indices that tell its draws apart;
- **a dataset's episodes**: ``(k,)`` for episode ``k`` of a generated dataset, the ``k``-th child
  of ``SeedSequence(seed).spawn(...)``, so that episode ``k`` depends on the master seed and
  ``k`` alone;
- **an episode's parts**: ``(WORLD,)`` and ``(SENSOR,)`` of the episode's own seed, the world's
  motion and the robot's sensor noise; ``(ANNOTATION_DRAW,)`` and ``(ANNOTATION,)``, the draw
  of its annotation model (when randomised) and that model's own random errors.

A key is the same key whatever the order in which the uses run, which is what lets a study run
its units in any order, on any number of processes, with the same result.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np

__all__ = [
    "ANNOTATION",
    "ANNOTATION_DRAW",
    "SEED_BITS",
    "SENSOR",
    "WORLD",
    "Role",
    "derive_int",
    "derive_rng",
    "derive_seed",
]

SEED_BITS = 63  # bits of a derived integer seed (a non-negative int64)

# The parts of one episode's seed (its spawn keys).
WORLD = 0
SENSOR = 1
ANNOTATION_DRAW = 2
ANNOTATION = 3


class Role(IntEnum):
    """The first spawn key of a study's master seed: which use a random stream serves.

    The values are part of every study's results (changing one changes its numbers); new roles
    take new values.
    """

    STRESS_TRAIN = 0  # the stress grid's training episodes: (role, scenario, episode)
    STRESS_TEST = 1  # its test episodes: (role, scenario or axis, level, episode)
    STRESS_PERTURB = 2  # its perturbations: (role, axis, episode)
    STRESS_BOOTSTRAP = 3  # its bootstrap intervals: (role, axis, detector)
    HRI_EPISODE = 4  # the HRI experiment's episodes: (role, scenario, episode)
    HRI_BOOTSTRAP = 5  # its bootstrap intervals: (role, row)
    TRACKER_NOISE_FIT = 6  # the fit of the training scenes' tracker noise to SALSA: (role,)
    TRAINING_NOISE = 7  # that noise on the demo's and sim2real's training scenes: (role, source)
    SIM2REAL_BOOTSTRAP = 8  # sim2real's bootstrap intervals: (role, dataset)
    SIM2REAL_PERIODS = 9  # sim2real's cross-period bootstrap: (role, held-out half)
    PAPER_RANDOM_SPLIT = 10  # the paper experiment's random-split diagnostic: (role,)
    BENCHMARK_BOOTSTRAP = 11  # the benchmark's intervals: (role, crc32 of the dataset's label)
    TEMPORAL_BOOTSTRAP = 12  # temporal scores' intervals over sequences: (role,) or (role, crc32)
    TEMPORAL_PARTY = 13  # the temporal experiment's party episodes: (role, episode)


def _key(keys: tuple[int, ...]) -> tuple[int, ...]:
    out = []
    for key in keys:
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)) or key < 0:
            raise ValueError(f"a spawn key must be a non-negative integer, got {key!r}")
        out.append(int(key))
    return tuple(out)


def derive_seed(seed: int, *keys: int) -> np.random.SeedSequence:
    """The seed sequence of one use of the master ``seed``: ``SeedSequence(seed,
    spawn_key=keys)``. Different keys give independent streams."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return np.random.SeedSequence(int(seed), spawn_key=_key(keys))


def derive_rng(seed: int, *keys: int) -> np.random.Generator:
    """A generator for one use of the master ``seed`` (`derive_seed`)."""
    return np.random.default_rng(derive_seed(seed, *keys))


def derive_int(seed: int, *keys: int) -> int:
    """An integer seed for one use of the master ``seed``: the first `SEED_BITS` bits of
    `derive_seed`'s state, for what takes an int (a scenario's seed, a dataset's episode)."""
    state = derive_seed(seed, *keys).generate_state(1, dtype=np.uint64)[0]
    return int(state >> np.uint64(64 - SEED_BITS))
