"""The original GCFF code's partitions of SALSA (``<shared>/reference/gcff-reference``), read."""

from __future__ import annotations

from pathlib import Path

Partition = tuple[tuple[int, ...], ...]


def read_reference_partitions(path: Path) -> list[tuple[tuple[str, float], Partition]]:
    """``session time id:label ...`` lines -> list of ((sequence, time), partition), groups in
    the order of their first member on the line."""
    out = []
    for line in path.read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        session, time, *pairs = line.split()
        groups: dict[int, list[int]] = {}
        for pair in pairs:
            person, label = pair.split(":")
            groups.setdefault(int(label), []).append(int(person))
        out.append(
            ((f"session{session}", round(float(time), 1)), tuple(map(tuple, groups.values())))
        )
    return out
