"""A venue twin's labelled synthetic data: `sim.generate` run with the twin's scenario, options,
annotation model and rate, into a folder of its own (resumed, never made twice)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from reform.frame import Dataset
from sim.twins.description import Twin

__all__ = ["DATA_FOLDER", "generate_twin", "twin_data", "twin_options"]

DATA_FOLDER = "twin-data"  # beside twin.json: the twin's generated dataset


def twin_options(
    twin: Twin, *, seed: int | None = None, episodes: int | None = None
) -> tuple[dict[str, Any], str]:
    """The scenario options ``twin``'s data are generated with, for ``seed`` and ``episodes``
    (default the twin's own), and a line saying what changed (empty when nothing did).

    The fit sized the twin's room so that every party of the twin's own seed and episodes fits
    (`sim.twins.fit.room_for_every_episode`). For another seed, or more episodes, the same rule
    grows the room until every party of those fits too.
    """
    from sim.twins.fit import VENUES, room_for_every_episode

    options = dict(twin.options)
    seed = twin.seed if seed is None else seed
    episodes = twin.episodes if episodes is None else episodes
    venue = VENUES.get(twin.scenario)
    if venue is None or (seed == twin.seed and episodes <= twin.episodes):
        return options, ""
    grown = room_for_every_episode(options, seed=seed, episodes=episodes, scenario=twin.scenario)
    room = venue.room
    if grown[room] == options[room]:
        return options, ""
    return grown, (
        f"the twin's room grew from {options[room]:g} m to {grown[room]:g} m so that every "
        f"party of seed {seed}'s {episodes} episodes fits (the rule that sized it for its own "
        f"seed, {twin.seed})"
    )


def generate_twin(
    twin: Twin,
    out_dir: str | os.PathLike[str],
    *,
    episodes: int | None = None,
    seed: int | None = None,
    n_jobs: int | None = None,
    progress: bool = False,
):
    """Generates (or resumes) the twin's dataset in ``out_dir``: ``episodes`` (default the
    twin's) episodes of its scenario with its options, annotated by its annotation model at its
    rate, seeded by ``seed`` (default the twin's, as `reform-sim generate --twin` does with its
    default ``--seed 0`` for a twin fitted with seed 0). Returns
    `sim.generate.GenerationReport`."""
    from sim.generate import generate_dataset

    options, _ = twin_options(twin, seed=seed, episodes=episodes)
    return generate_dataset(
        twin.scenario,
        episodes=twin.episodes if episodes is None else episodes,
        seed=twin.seed if seed is None else seed,
        out_dir=out_dir,
        options=options,
        rate=twin.rate_hz,
        annotation=None if twin.annotation.identity else twin.annotation,
        n_jobs=n_jobs,
        progress=progress,
    )


def twin_data(
    twin: Twin,
    out_dir: str | os.PathLike[str],
    *,
    episodes: int | None = None,
    seed: int | None = None,
    n_jobs: int | None = None,
    progress: bool = False,
) -> Dataset:
    """The twin's dataset in ``out_dir``, generated there first when it is not yet."""
    from reform.datasets import read_parquet

    generate_twin(twin, out_dir, episodes=episodes, seed=seed, n_jobs=n_jobs, progress=progress)
    return read_parquet(Path(out_dir))
