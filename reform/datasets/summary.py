"""What a dataset holds, in numbers: frames, people, annotation, group sizes, loader report."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from reform.frame import Dataset

__all__ = ["CAUTIONS", "repairs_line", "summarise"]


# What a loader's report may say beside its repairs, when what it read casts doubt on the file:
# the unit it assumed, ground truth that stops before the features.
CAUTIONS = ("units_caution", "groundtruth_caution")


def repairs_line(dataset: Dataset, label: str) -> str | None:
    """One line saying what the loader repaired in ``dataset`` (``label``: how the user named
    it), the first repair of the first kind quoted, and its cautions (`CAUTIONS`); None when
    it repaired nothing and has no caution. A repair is what the field's files need read (a
    NaN pose dropped, ground truth naming someone absent): counted in the loader's report, and
    said, never silent; a caution is what casts doubt on the file (the unit assumed for a
    GCFF folder with NaN poses, ground truth that stops before the features)."""
    report = dataset.metadata.get("report")
    if not isinstance(report, dict):
        return None
    repairs = report.get("repairs")
    cautions = [report[key] for key in CAUTIONS if isinstance(report.get(key), str)]
    if not repairs and not cautions:
        return None
    parts = []
    if repairs:
        counts = ", ".join(f"{kind} {count}" for kind, count in repairs.items())
        first = report.get("first_repair", {}).get(next(iter(repairs)), "")
        parts.append(
            f"read with repairs (--strict refuses them): {counts}"
            + (f"; the first: {first}" if first else "")
        )
    return f"note: {label}: " + "; ".join(parts + cautions)


def summarise(dataset: Dataset) -> dict[str, Any]:
    """A JSON-ready summary of ``dataset``.

    Keys: ``name``, ``source``, ``units``, ``frames``, ``annotated_frames``, ``sequences``
    (name -> ``{"frames", "annotated_frames", "duration_s"}``), ``people`` (distinct ids, and
    per-frame ``min``/``median``/``max``), ``robots`` (frames with a robot), ``heads``
    (person-frames with an observed head, and without head data or with a NaN head),
    ``group_sizes`` (size -> number of groups over the annotated frames, singletons included,
    keys as strings), ``fformations`` (groups of two or more), and ``report`` (the loader's
    counts, when it made any).
    """
    if not isinstance(dataset, Dataset):
        raise TypeError(
            f"summarise: dataset must be a reform.Dataset, got {type(dataset).__name__}"
        )
    frames = dataset.frames
    annotated = [f for f in frames if f.groups is not None]
    sequences: dict[str, dict[str, Any]] = {}
    for frame in frames:
        entry = sequences.setdefault(
            frame.sequence,
            {"frames": 0, "annotated_frames": 0, "start": frame.time, "end": frame.time},
        )
        entry["frames"] += 1
        entry["annotated_frames"] += frame.groups is not None
        entry["start"] = min(entry["start"], frame.time)
        entry["end"] = max(entry["end"], frame.time)
    for entry in sequences.values():
        entry["duration_s"] = round(entry.pop("end") - entry.pop("start"), 6)

    counts = np.array([f.n_people for f in frames], dtype=np.int64)
    ids = set()
    observed = missing = absent = 0
    for frame in frames:
        ids.update(frame.ids.tolist())
        if frame.head_yaw is None:
            absent += frame.n_people
        else:
            nan = int(np.isnan(frame.head_yaw).sum())
            missing += nan
            observed += frame.n_people - nan
    sizes = Counter(len(g) for f in annotated for g in f.partition())
    report = dataset.metadata.get("report")
    return {
        "name": dataset.name,
        "source": dataset.source,
        "units": dataset.units,
        "frames": len(frames),
        "annotated_frames": len(annotated),
        "sequences": sequences,
        "people": {
            "distinct_ids": len(ids),
            "min": int(counts.min()) if counts.size else 0,
            "median": float(np.median(counts)) if counts.size else 0.0,
            "max": int(counts.max()) if counts.size else 0,
            "person_frames": int(counts.sum()),
        },
        "robots": sum(1 for f in frames if np.any(f.is_robot)),
        "heads": {"observed": observed, "not_observed": missing, "no_head_data": absent},
        "group_sizes": {str(k): v for k, v in sorted(sizes.items())},
        "fformations": sum(v for k, v in sizes.items() if k >= 2),
        "report": None if report is None else dict(report),
    }
