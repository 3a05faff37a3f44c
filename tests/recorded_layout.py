"""Reads an .rrd file's default layout (its blueprint store) and checks it against the data.

`panels(path)` decodes the views the layout shows (reached from the viewport through its
containers): class, name, origin, contents queries and y range. `entities_shown(panel, data)`
resolves a view's contents queries against the recording's entity paths as the viewer does
(``$origin`` substituted, ``path/**`` for a subtree, ``- ...`` to leave out).
`assert_every_panel_holds_data(path)` asserts that each panel shows entities holding data and
that each plot's y range holds every value it draws.
"""

from __future__ import annotations

import uuid
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import pyarrow as pa
from rerun.chunk import RrdReader


@dataclass
class Panel:
    view_id: str
    kind: str
    name: str
    origin: str
    contents: list[str] = field(default_factory=lambda: ["$origin/**"])
    y_range: tuple[float, float] | None = None


def _blueprint_rows(path: Path) -> dict[str, dict[str, object]]:
    reader = RrdReader(path)
    store = reader.blueprints()[0]  # a file of several recordings holds one layout each
    rows: dict[str, dict[str, object]] = defaultdict(dict)
    for chunk in reader.stream(store=store):
        batch = chunk.to_record_batch()
        for name, column in zip(batch.schema.names, batch.columns, strict=True):
            if name.startswith("rerun.controls") or pa.types.is_temporal(column.type):
                continue
            rows[str(chunk.entity_path)][name] = column.to_pylist()[-1]
    return rows


def panels(path: Path) -> list[Panel]:
    """The views of the file's default layout, in the order the containers hold them."""
    rows = _blueprint_rows(path)
    root = uuid.UUID(bytes=bytes(rows["/viewport"]["ViewportBlueprint:root_container"][0]))
    out: list[Panel] = []

    def visit(item: str) -> None:
        kind, _, key = item.partition("/")
        if kind == "container":
            for child in rows[f"/container/{key}"]["ContainerBlueprint:contents"]:
                visit(child)
            return
        view = rows[f"/view/{key}"]
        panel = Panel(
            view_id=key,
            kind=view["ViewBlueprint:class_identifier"][0],
            name=view["ViewBlueprint:display_name"][0],
            origin=view["ViewBlueprint:space_origin"][0],
        )
        contents = rows.get(f"/view/{key}/ViewContents", {}).get("ViewContents:query")
        if contents:
            panel.contents = list(contents)
        axis = rows.get(f"/view/{key}/ScalarAxis", {}).get("ScalarAxis:range")
        if axis:
            panel.y_range = (float(axis[0][0]), float(axis[0][1]))
        out.append(panel)

    visit(f"container/{root}")
    return out


class RecordedData:
    """The recording store of an .rrd: per entity, whether it holds data, and its scalars."""

    def __init__(self, path: Path, recording_id: str | None = None) -> None:
        self.entities: set[str] = set()
        self.scalars: dict[str, list[float]] = defaultdict(list)
        reader = RrdReader(path)
        stores = reader.recordings()
        store = next(s for s in stores if recording_id in (None, s.recording_id))
        for chunk in reader.stream(store=store):
            entity = str(chunk.entity_path)
            if chunk.num_rows:
                self.entities.add(entity)
            batch = chunk.to_record_batch()
            if "Scalars:scalars" in batch.schema.names:
                column = batch.column("Scalars:scalars").to_pylist()
                self.scalars[entity] += [v for row in column for v in (row or [])]


def _matches(pattern: str, entity: str) -> bool:
    if pattern.endswith("/**"):
        base = pattern[: -len("/**")]
        return entity == base or entity.startswith(base + "/")
    return entity == pattern


def entities_shown(panel: Panel, data: RecordedData) -> set[str]:
    """The recording's entities the panel's contents queries take in."""
    keep: set[str] = set()
    drop: set[str] = set()
    for query in panel.contents:
        query = query.strip()
        negative = query.startswith("- ")
        pattern = query.removeprefix("- ").removeprefix("+ ").strip()
        pattern = pattern.replace("$origin", panel.origin.rstrip("/"))
        if not pattern.startswith("/"):
            pattern = "/" + pattern
        hit = {e for e in data.entities if _matches(pattern, e)}
        (drop if negative else keep).update(hit)
    return keep - drop


def assert_every_panel_holds_data(path: Path, recording_id: str | None = None) -> list[Panel]:
    """Every panel of the layout shows entities holding data (in the recording
    ``recording_id``, default the file's first), and each plot has a y range holding every
    value it draws; returns the panels."""
    data = RecordedData(path, recording_id)
    shown = panels(path)
    assert shown, f"{path}: the layout shows no panel"
    for panel in shown:
        entities = entities_shown(panel, data)
        assert entities, f"{panel.name!r} ({panel.origin}, {panel.contents}) shows no data"
        if panel.kind != "TimeSeries":
            continue
        values = [v for e in sorted(entities) for v in data.scalars.get(e, [])]
        assert values, f"{panel.name!r} shows no scalars"
        assert panel.y_range is not None, f"{panel.name!r} has no y range"
        low, high = panel.y_range
        outside = [v for v in values if not low <= v <= high]
        assert not outside, f"{panel.name!r}: values {outside[:5]} outside {panel.y_range}"
        assert high > low
    return shown
