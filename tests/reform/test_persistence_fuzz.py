"""Any change to a model file gives a model that predicts or one clean ValueError, never another
exception and never a crash.

Property-based: hypothesis starts from real small model files written by ``save_model`` (one per
ready-made classifier) and changes the archive's bytes, the bytes of its ``schema.json``
(re-zipped), the values inside ``schema.json`` (any JSON, or a value taken from elsewhere in the
file, such as another object's ``__id__``), and the bytes of its ``.npy`` arrays (a tree's
nodes, a neighbour tree's index), which scikit-learn's compiled predictors read unchecked.
"""

from __future__ import annotations

import copy
import io
import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from toy_scenes import toy_frames

from reform import Reform
from reform.classifiers import BAGGED_TREES, LOGISTIC_REGRESSION, WEIGHTED_KNN, make_classifier
from reform.persistence import load_model, save_model

SETTINGS = settings(max_examples=60, deadline=None)

# Small models, so that a change lands on what matters: 2 trees of small leaves, a KNN of few
# pairs, a logistic regression.
CLASSIFIERS = {
    BAGGED_TREES: {"n_estimators": 2, "min_samples_leaf": 5},
    WEIGHTED_KNN: {"n_neighbors": 3},
    LOGISTIC_REGRESSION: {},
}
FRAMES = toy_frames(7, 3, sizes=(2, 3), loners=1)


@dataclass(frozen=True)
class ModelFile:
    folder: Path
    data: bytes  # the file save_model wrote
    members: dict[str, bytes]  # its archive's members
    schema: dict  # schema.json, parsed
    places: tuple[tuple, ...]  # paths (keys and indices) to every value in schema.json

    def write(self, data: bytes) -> Path:
        path = self.folder / "changed.skops"
        path.write_bytes(data)
        return path

    def rezip(self, **members: bytes) -> Path:
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w") as archive:
            for name, content in {**self.members, **members}.items():
                archive.writestr(name, content)
        return self.write(buffer.getvalue())


def _places(value, prefix=()) -> list[tuple]:
    out = []
    stack = [(value, prefix)]
    while stack:
        item, path = stack.pop()
        children = (
            item.items()
            if isinstance(item, dict)
            else enumerate(item)
            if isinstance(item, list)
            else ()
        )
        for key, child in children:
            out.append((*path, key))
            stack.append((child, (*path, key)))
    return out


@pytest.fixture(scope="module", params=list(CLASSIFIERS))
def model_file(request, tmp_path_factory) -> ModelFile:
    name = request.param
    model = Reform(make_classifier(name, **CLASSIFIERS[name])).fit(toy_frames(0, 12))
    folder = tmp_path_factory.mktemp(name)
    path = save_model(model, folder / "model.skops")
    with zipfile.ZipFile(path) as archive:
        members = {member: archive.read(member) for member in archive.namelist()}
    schema = json.loads(members["schema.json"])
    return ModelFile(folder, path.read_bytes(), members, schema, tuple(_places(schema)))


def _loads_and_predicts_or_refuses(path: Path) -> None:
    try:
        model = load_model(path)
    except ValueError as exc:
        message = str(exc)
        assert "\n" not in message and len(message) < 2000, message
        assert str(path) in message, message
        return
    assert isinstance(model, Reform)
    partitions = model.predict(FRAMES)
    assert [sorted(person for group in p for person in group) for p in partitions] == [
        sorted(frame.ids.tolist()) for frame in FRAMES
    ]


EDITS = st.lists(st.tuples(st.integers(0, 2**31), st.integers(0, 255)), min_size=1, max_size=6)


def _apply(data: bytes, edits, kind: str) -> bytes:
    changed = bytearray(data)
    for position, value in edits:
        at = position % (len(changed) + 1)
        if kind == "replace" and at < len(changed):
            changed[at] = value
        elif kind == "insert":
            changed[at:at] = bytes([value])
        elif kind == "delete":
            del changed[at : at + 1 + value % 8]
    return bytes(changed)


KINDS = st.sampled_from(["replace", "insert", "delete"])


@SETTINGS
@given(edits=EDITS, kind=KINDS, cut=st.one_of(st.none(), st.integers(0, 2**31)))
def test_archive_bytes(model_file, edits, kind, cut):
    data = _apply(model_file.data, edits, kind)
    if cut is not None:
        data = data[: cut % (len(data) + 1)]
    _loads_and_predicts_or_refuses(model_file.write(data))


@SETTINGS
@given(edits=EDITS, kind=KINDS)
def test_schema_bytes(model_file, edits, kind):
    schema = _apply(model_file.members["schema.json"], edits, kind)
    _loads_and_predicts_or_refuses(model_file.rezip(**{"schema.json": schema}))


JSON_VALUES = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        st.integers(-(2**70), 2**70),
        st.floats(allow_nan=True, allow_infinity=True),
        st.sampled_from(
            [
                "",
                "0",
                "1",
                "-1",
                "1e400",
                "nan",
                "[[[[",
                '"x"',
                "numpy",
                "sklearn",
                "NdArrayNode",
                "TreeNode",
                "ObjectNode",
                "JsonNode",
                "CachedNode",
                "builtins",
                "list",
                "dict",
                "numpy",
                "ndarray",
                "9" * 5000,
            ]
        ),
        st.text(max_size=12),
    ),
    lambda children: st.one_of(
        st.lists(children, max_size=3), st.dictionaries(st.text(max_size=8), children, max_size=3)
    ),
    max_leaves=8,
)


def _at(schema: dict, place: tuple):
    *parents, key = place
    container = schema
    for step in parents:
        container = container[step]
    return container, key


@SETTINGS
@given(data=st.data())
def test_schema_values(model_file, data):
    schema = copy.deepcopy(model_file.schema)
    for _ in range(data.draw(st.integers(1, 3), label="changes")):
        places = _places(schema)
        if not places:
            break
        container, key = _at(schema, data.draw(st.sampled_from(places), label="place"))
        action = data.draw(st.sampled_from(["set", "copy", "delete"]), label="action")
        if action == "set":
            container[key] = data.draw(JSON_VALUES, label="value")
        elif action == "copy":  # another value of the file here: an __id__, a loader, a node
            source, source_key = _at(schema, data.draw(st.sampled_from(places), label="from"))
            container[key] = copy.deepcopy(source[source_key])
        elif isinstance(container, dict):
            del container[key]
        else:
            container.pop(key)
    text = json.dumps(schema).encode()
    _loads_and_predicts_or_refuses(model_file.rezip(**{"schema.json": text}))


@SETTINGS
@given(data=st.data(), edits=EDITS, kind=st.sampled_from(["replace", "replace", "delete"]))
def test_array_bytes(model_file, data, edits, kind):
    arrays = sorted(name for name in model_file.members if name.endswith(".npy"))
    name = data.draw(st.sampled_from(arrays), label="array")
    original = model_file.members[name]
    header = original.index(b"\n") + 1  # the .npy header ends with a newline
    body = data.draw(st.booleans(), label="in the data")
    if body and len(original) > header:  # keep the header: the values themselves change
        changed = original[:header] + _apply(original[header:], edits, "replace")
    else:
        changed = _apply(original, edits, kind)
    _loads_and_predicts_or_refuses(model_file.rezip(**{name: changed}))
