"""`sim.generate.generate_dataset` as the tests run it: one worker, no progress bar."""

from __future__ import annotations

import os
from typing import Any

from sim.generate import GenerationReport, generate_dataset

QUIET = {"n_jobs": 1, "progress": False}


def generate_quietly(
    scenario: str, out_dir: str | os.PathLike[str], **kwargs: Any
) -> GenerationReport:
    """Generates ``scenario`` into ``out_dir`` with one worker and no progress bar; ``kwargs``
    are `generate_dataset`'s other arguments (an ``n_jobs`` or ``progress`` there wins)."""
    return generate_dataset(scenario, out_dir=out_dir, **(QUIET | kwargs))
