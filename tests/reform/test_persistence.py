"""Model files: skops round trips, identical predictions; foreign, old and broken files refused."""

from __future__ import annotations

import functools
import io
import json
import struct
import zipfile
import zlib
from fractions import Fraction

import numpy as np
import pytest
import sklearn
import skops.io as sio
from sklearn.exceptions import NotFittedError
from sklearn.linear_model import LogisticRegression
from sklearn.tree import DecisionTreeClassifier
from toy_scenes import toy_frames
from traced import traced_peak

import reform
from reform import Reform, persistence
from reform.classifiers import CLASSIFIERS, make_classifier
from reform.persistence import FORMAT, FORMAT_VERSION, load_model, model_info, save_model


@functools.cache
def fitted(name: str) -> Reform:
    return Reform(make_classifier(name)).fit(toy_frames(0, 60))


@pytest.mark.parametrize("name", list(CLASSIFIERS))
def test_round_trip_gives_identical_predictions(name, tmp_path):
    model = fitted(name)
    path = save_model(model, tmp_path / "model.skops")
    assert zipfile.is_zipfile(path)  # a skops archive, not a pickle
    loaded = load_model(path)
    assert isinstance(loaded, Reform)
    assert loaded is not model
    frames = toy_frames(9, 30, sizes=(2, 3, 4), loners=3)
    assert loaded.predict(frames) == model.predict(frames)
    assert loaded.get_params(deep=False)["reconstruction"] == model.reconstruction
    assert loaded.training_summary_ == model.training_summary_


def test_file_says_what_it_holds(tmp_path):
    path = save_model(fitted("bagged-trees"), tmp_path / "model.skops")
    info = model_info(path)
    assert info["format"] == FORMAT
    assert info["versions"]["reform_sim"] == reform.__version__
    assert info["versions"]["scikit_learn"] == sklearn.__version__
    assert info["features"] == ["distance", "effort_angle"]
    assert info["classifier"] == "BaggingClassifier"
    assert info["training"]["frames"] == 60
    assert info["training"]["pairs"] == 60 * 55


@pytest.mark.parametrize(
    "options",
    [
        {"features": "relative"},
        {"reconstruction": "correlation", "threshold": 0.4},
        {"calibration": "sigmoid"},
        {"classifier": "weighted-knn", "calibration": "isotonic", "reconstruction": "correlation"},
        {"classifier": "logistic-regression", "features": "relative", "calibration": "isotonic"},
    ],
    ids=lambda options: ",".join(f"{k}={v}" for k, v in options.items()),
)
def test_options_round_trip_and_are_described(options, tmp_path):
    options = dict(options)
    classifier = make_classifier(options.pop("classifier", "bagged-trees"))
    model = Reform(classifier, **options).fit(toy_frames(0, 60))
    path = save_model(model, tmp_path / "model.skops")
    loaded = load_model(path)
    frames = toy_frames(9, 30, sizes=(2, 3, 4), loners=3)
    assert loaded.predict(frames) == model.predict(frames)
    pairs = zip(loaded.predict_pair_proba(frames), model.predict_pair_proba(frames), strict=True)
    for a, b in pairs:
        np.testing.assert_array_equal(a, b)
    assert loaded.get_params(deep=False) | {"classifier": None} == model.get_params(deep=False) | {
        "classifier": None
    }
    info = model_info(path)
    assert info["features"] == list(model.features_)
    assert info["reconstruction"] == model.reconstruction
    assert info["threshold"] == model.threshold
    assert info["calibration"] == model.calibration


def test_a_default_model_says_it_is_uncalibrated(tmp_path):
    path = save_model(fitted("bagged-trees"), tmp_path / "model.skops")
    assert model_info(path)["calibration"] is None
    assert load_model(path).calibration is None
    with zipfile.ZipFile(path) as archive:  # the option is left out of a default file
        assert '"calibration"' not in archive.read("schema.json").decode()


def test_a_calibration_that_disagrees_with_its_classifier_is_refused(tmp_path):
    model = Reform(calibration="sigmoid").fit(toy_frames(0, 30))
    vars(model).update(calibration="isotonic")
    path = tmp_path / "model.skops"
    path.write_bytes(sio.dumps(payload(model)))
    with pytest.raises(ValueError, match="calibration 'isotonic' disagrees with the classifier"):
        load_model(path)


def test_the_compiled_table_is_not_stored(tmp_path):
    model = fitted("bagged-trees")
    assert model.compile()._compiled is not None
    path = save_model(model, tmp_path / "model.skops")
    assert path.stat().st_size < 2_000_000
    with zipfile.ZipFile(path) as archive:
        schema = archive.read("schema.json").decode()
        assert "_compiled" not in schema and "_sklearn_s" not in schema
    loaded = load_model(path)  # compiled again from its own classifier once it pays
    assert loaded._compiled is None
    assert loaded.compile()._compiled is not None
    frames = toy_frames(3, 2)
    assert loaded.predict(frames) == model.predict(frames)


def payload(model: Reform, **changes) -> dict:
    data = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "versions": {"reform_sim": reform.__version__, "scikit_learn": sklearn.__version__},
        "model": model,
    }
    data.update(changes)
    return data


def test_foreign_types_are_refused(tmp_path):
    path = tmp_path / "evil.skops"
    sio.dump(payload(fitted("logistic-regression"), extra=Fraction(1, 3)), path)
    refused(load_model, path, match=r"refusing to load: .*\['fractions.Fraction'\]")
    assert isinstance(load_model(path, trusted=["fractions.Fraction"]), Reform)


def test_other_versions_are_refused(tmp_path):
    model = fitted("logistic-regression")
    old = tmp_path / "old.skops"
    sio.dump(payload(model, versions={"reform_sim": "0.0.1", "scikit_learn": "1.9.1"}), old)
    refused(load_model, old, match=r"written by reform-sim 0.0.1, this is reform-sim")
    other_sklearn = tmp_path / "sklearn.skops"
    versions = {"reform_sim": reform.__version__, "scikit_learn": "1.5.2"}
    sio.dump(payload(model, versions=versions), other_sklearn)
    refused(load_model, other_sklearn, match="written with scikit-learn 1.5.2")
    newer_format = tmp_path / "format.skops"
    sio.dump(payload(model, format_version=99), newer_format)
    refused(load_model, newer_format, match="format version 99")


def test_files_that_are_not_reform_models_are_refused(tmp_path):
    plain = tmp_path / "plain.skops"
    sio.dump(LogisticRegression(), plain)
    refused(load_model, plain, match="not a REFORM model file")
    text = tmp_path / "model.skops"
    text.write_text("hello")
    refused(load_model, text, match="not a skops model file")
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_model(tmp_path / "missing.skops")
    wrong = tmp_path / "wrong.skops"
    sio.dump(payload(LogisticRegression()), wrong)
    refused(load_model, wrong, match="model is a LogisticRegression, not a reform.Reform")


def test_only_fitted_reform_models_are_saved(tmp_path):
    with pytest.raises(NotFittedError):
        save_model(Reform(), tmp_path / "m.skops")
    with pytest.raises(TypeError, match="model must be a reform.Reform, got LogisticRegression"):
        save_model(LogisticRegression(), tmp_path / "m.skops")
    assert not (tmp_path / "m.skops").exists()


def fresh(name: str = "logistic-regression") -> Reform:
    """A fitted model of our own, free to be altered (``fitted`` is shared between tests)."""
    return Reform(make_classifier(name)).fit(toy_frames(0, 60))


def _features_disagree() -> dict:
    model = fresh("bagged-trees")  # fitted on distance and effort_angle
    model.features_ = ("distance",)
    return payload(model)


def _unknown_features() -> dict:
    model = fresh()
    model.features_ = ("distance", "loudness")
    return payload(model)


def _other_classes() -> dict:
    model = fresh()
    x = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]])
    model.classifier_ = LogisticRegression().fit(x, np.array([0, 1, 2, 2]))
    return payload(model)


def _unfitted_classifier() -> dict:
    model = fresh()
    model.classifier_ = LogisticRegression()
    return payload(model)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        pytest.param(
            _features_disagree,
            r"inconsistent model: features_ \['distance'\] gives 1 feature\(s\) per pair, "
            r"expected the classifier to take as many, found a BaggingClassifier fitted on 2 "
            r"\(n_features_in_\)",
            id="features-disagree-with-classifier",
        ),
        pytest.param(
            _unknown_features,
            r"the model's features_ are not valid: features must be among .*, got 'loudness'",
            id="unknown-features",
        ),
        pytest.param(
            lambda: payload(fresh(), features=["distance", "head_distance"]),
            r"the file lists features \['distance', 'head_distance'\], expected the model's own "
            r"features_ \['distance', 'effort_angle'\]",
            id="file-lists-other-features",
        ),
        pytest.param(
            _other_classes,
            r"inconsistent model: expected a pair classifier of classes \[0, 1\] \(apart, "
            r"together\), found a LogisticRegression with classes_ \[0, 1, 2\]",
            id="other-classes",
        ),
        pytest.param(
            lambda: payload(Reform()),
            r"expected a fitted reform\.Reform, found an unfitted one \(no classifier_ or "
            r"features_\)",
            id="unfitted-model",
        ),
        pytest.param(
            _unfitted_classifier,
            r"expected a fitted pair classifier in the model, found an unfitted "
            r"LogisticRegression",
            id="unfitted-classifier",
        ),
    ],
)
def test_a_broken_model_file_is_refused_naming_it(make, message, tmp_path):
    path = tmp_path / "broken.skops"
    sio.dump(make(), path)
    refused(load_model, path, match=r"broken\.skops: " + message)
    refused(model_info, path, match=message)


def test_a_folder_is_not_a_model_file(tmp_path):
    folder = tmp_path / "model.skops"
    folder.mkdir()
    refused(load_model, folder, match=r"model file .*model\.skops is a folder: expected a ")
    refused(model_info, folder, match="is a folder")


def test_the_command_line_says_the_model_is_a_folder(tmp_path, capsys):
    from reform.datasets import write_parquet
    from sim.cli import main

    data = tmp_path / "toy.parquet"
    write_parquet(reform.Dataset(frames=tuple(toy_frames(1, 4)), name="toy"), data)
    folder = tmp_path / "model.skops"
    folder.mkdir()
    assert main(["evaluate", "--model", str(folder), "--data", str(data)]) == 2
    assert "model.skops is a folder: expected a skops file" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# Model files checked whole: limits before inflating, the schema's shape, the estimators' arrays


def rewrite(source, target, *, schema=None, members=None, compression=zipfile.ZIP_STORED):
    """``source``'s archive written again to ``target``: ``schema(dict)`` edits schema.json in
    place, ``members`` maps member names to new bytes."""
    with zipfile.ZipFile(source) as archive:
        contents = {name: archive.read(name) for name in archive.namelist()}
    if schema is not None:
        state = json.loads(contents["schema.json"])
        schema(state)
        contents["schema.json"] = json.dumps(state).encode()
    contents.update(members or {})
    with zipfile.ZipFile(target, "w", compression=compression) as archive:
        for name, content in contents.items():
            archive.writestr(name, content)
    return target


def nodes(state, **fields):
    """Every object of a schema whose fields equal ``fields``, depth first."""
    stack = [state]
    while stack:
        item = stack.pop()
        if isinstance(item, dict):
            if all(item.get(key) == value for key, value in fields.items()):
                yield item
            stack.extend(reversed(list(item.values())))
        elif isinstance(item, list):
            stack.extend(reversed(item))


def attribute(state, name):
    """The first object stored under the dictionary key ``name`` in a schema."""
    for node in nodes(state, __loader__="DictNode"):
        if name in node["content"]:
            return node["content"][name]
    raise KeyError(name)


def one_line(exc_info) -> str:
    message = str(exc_info.value)
    assert "\n" not in message and len(message) < 1000, message
    return message


def refused(read, *args, match: str, **kwargs) -> str:
    """``read(*args, **kwargs)`` raises a ValueError matching ``match``, in one line: the line."""
    with pytest.raises(ValueError, match=match) as info:
        read(*args, **kwargs)
    return one_line(info)


@pytest.fixture(scope="module")
def small_file(tmp_path_factory):
    return save_model(fitted("logistic-regression"), tmp_path_factory.mktemp("m") / "lr.skops")


@pytest.fixture(scope="module")
def trees_file(tmp_path_factory):
    return save_model(fitted("bagged-trees"), tmp_path_factory.mktemp("m") / "trees.skops")


def test_a_file_above_the_size_limit_is_refused_naming_the_keyword(small_file):
    size = small_file.stat().st_size
    refused(
        load_model,
        small_file,
        max_bytes=1000,
        match=rf"lr\.skops: the file is {size:,} bytes, above the "
        r"limit of 1,000 bytes; .*max_bytes=\.\.\. \(load_model, model_info\)",
    )
    refused(model_info, small_file, max_bytes=1000, match="above the limit of 1,000 bytes")
    assert isinstance(load_model(small_file, max_bytes=size), Reform)
    refused(
        load_model,
        small_file,
        max_bytes=0,
        match="max_bytes must be a positive number of bytes, got 0",
    )


def test_members_inflating_above_the_limit_are_refused(small_file, tmp_path):
    deflated = rewrite(small_file, tmp_path / "d.skops", compression=zipfile.ZIP_DEFLATED)
    with zipfile.ZipFile(deflated) as archive:
        inflated = sum(info.file_size for info in archive.infolist())
    limit = deflated.stat().st_size + 10  # the file fits, its members do not
    refused(
        load_model,
        deflated,
        max_bytes=limit,
        match=rf"the archive's members inflate to {inflated:,} bytes, "
        rf"above the limit of {limit:,} bytes; .*max_bytes=",
    )


def test_a_deflated_model_loads_and_predicts(small_file, tmp_path):
    deflated = rewrite(small_file, tmp_path / "d.skops", compression=zipfile.ZIP_DEFLATED)
    assert deflated.stat().st_size < small_file.stat().st_size
    frames = toy_frames(9, 5)
    assert load_model(deflated).predict(frames) == fitted("logistic-regression").predict(frames)


def _zeros_deflated(head: bytes, n_zeros: int) -> bytes:
    """A raw deflate stream of ``head`` followed by ``n_zeros`` zero bytes."""
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    parts = [compressor.compress(head)]
    zeros = bytes(1 << 20)
    for _ in range(n_zeros >> 20):
        parts.append(compressor.compress(zeros))
    parts.append(compressor.flush())
    return b"".join(parts)


def _splice_member(data: bytes, name: str, raw: bytes, crc: int, size: int) -> bytes:
    """A deflated zip ``data`` whose member ``name`` holds the deflate stream ``raw`` while its
    entries claim ``crc`` and ``size`` (its local header and central directory entry patched)."""
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        members = archive.infolist()
    body, directory = bytearray(), bytearray()  # local headers and data; the central directory
    with zipfile.ZipFile(io.BytesIO(data)) as source:
        for info in members:
            encoded = info.filename.encode()
            if info.filename == name:
                content, entry_crc, entry_size = raw, crc, size
            else:
                content = zlib.compress(source.read(info.filename), 9)[2:-4]
                entry_crc = zlib.crc32(source.read(info.filename))
                entry_size = info.file_size
            offset = len(body)
            body += (
                struct.pack(
                    "<4s5H3L2H",
                    b"PK\x03\x04",
                    20,
                    0,
                    8,
                    0,
                    0,
                    entry_crc,
                    len(content),
                    entry_size,
                    len(encoded),
                    0,
                )
                + encoded
                + content
            )
            directory += (
                struct.pack(
                    "<4s6H3L5HLL",
                    b"PK\x01\x02",
                    20,
                    20,
                    0,
                    8,
                    0,
                    0,
                    entry_crc,
                    len(content),
                    entry_size,
                    len(encoded),
                    0,
                    0,
                    0,
                    0,
                    0,
                    offset,
                )
                + encoded
            )
    end = struct.pack(
        "<4s4H2LH", b"PK\x05\x06", 0, 0, len(members), len(members), len(directory), len(body), 0
    )
    return bytes(body + directory + end)


def test_a_member_inflating_beyond_its_entry_is_read_no_further(small_file, tmp_path):
    # zipfile inflates a whole member before cutting it to its entry's size: this member
    # carries 64 MiB of zeros after the array its entry describes, CRC and size matching.
    with zipfile.ZipFile(small_file) as archive:
        name = next(n for n in archive.namelist() if n.endswith(".npy"))
        array = archive.read(name)
    bomb = _zeros_deflated(array, 64 << 20)
    path = tmp_path / "bomb.skops"
    path.write_bytes(
        _splice_member(small_file.read_bytes(), name, bomb, zlib.crc32(array), len(array))
    )
    assert path.stat().st_size < 300_000
    model, peak = traced_peak(lambda: load_model(path))
    assert peak < 16 << 20, f"{peak:,} bytes at the peak"
    assert model.predict(toy_frames(9, 3)) == fitted("logistic-regression").predict(
        toy_frames(9, 3)
    )


def test_a_member_claiming_more_than_it_holds_is_refused(small_file, tmp_path):
    with zipfile.ZipFile(small_file) as archive:
        name = next(n for n in archive.namelist() if n.endswith(".npy"))
        array = archive.read(name)
    raw = zlib.compress(array, 9)[2:-4]
    path = tmp_path / "short.skops"
    path.write_bytes(
        _splice_member(small_file.read_bytes(), name, raw, zlib.crc32(array), len(array) + 100)
    )
    refused(
        load_model,
        path,
        match=rf"short\.skops: archive member '{name}' (is corrupt|"
        rf"holds {len(array):,} bytes, its entry says {len(array) + 100:,})",
    )
    path.write_bytes(_splice_member(small_file.read_bytes(), name, raw, 12345, len(array)))
    refused(load_model, path, match=rf"archive member '{name}' is corrupt: BadZipFile: Bad CRC-32")


def test_a_decompression_bomb_is_refused_by_its_ratio(small_file, tmp_path):
    path = rewrite(
        small_file,
        tmp_path / "bomb.skops",
        members={"padding.bin": bytes(64 << 20)},
        compression=zipfile.ZIP_DEFLATED,
    )
    refused(
        load_model,
        path,
        max_bytes=1 << 30,
        match=r"bomb\.skops: the archive's members inflate to "
        r"[\d,]+ bytes from a file of [\d,]+ \([\d,]+ to 1, above the limit of "
        r"100 to 1\): a decompression bomb",
    )


def _first_entry(offset: int, value: int):
    """Patches a 2-byte field of the first central directory entry (8: flags, 10: method)."""

    def patch(data: bytes) -> bytes:
        patched = bytearray(data)
        struct.pack_into("<H", patched, data.index(b"PK\x01\x02") + offset, value)
        return bytes(patched)

    return patch


@pytest.mark.parametrize(
    ("make", "message"),
    [
        pytest.param(
            _first_entry(10, zipfile.ZIP_BZIP2),
            r"archive member '.*' is compressed with method 12; model files are stored",
            id="bzip2-member",
        ),
        pytest.param(
            _first_entry(10, 99),
            r"archive member '.*' is compressed with method 99",
            id="unknown-compression",
        ),
        pytest.param(
            _first_entry(8, 0x1),
            r"archive member '.*' is encrypted; model files are not",
            id="encrypted-member",
        ),
        pytest.param(
            lambda data: data[:-22] + b"PK\x06\x07" + bytes(16) + data[-22:],
            r"a ZIP64 archive; model files stay below 4 GiB",
            id="zip64",
        ),
        pytest.param(
            lambda data: data[: len(data) // 2],
            r"not a skops model file \(not a zip archive\)",
            id="truncated",
        ),
    ],
)
def test_archives_save_model_never_writes_are_refused(small_file, tmp_path, make, message):
    path = tmp_path / "odd.skops"
    path.write_bytes(make(small_file.read_bytes()))
    refused(load_model, path, match=r"odd\.skops: .*" + message)


def test_member_count_and_directory_limits(small_file, tmp_path, monkeypatch):
    with zipfile.ZipFile(small_file) as archive:
        count = len(archive.infolist())
    monkeypatch.setattr(persistence, "MAX_MODEL_MEMBERS", count - 1)
    refused(
        load_model,
        small_file,
        match=rf"the archive holds {count:,} members, above the limit "
        rf"of {count - 1:,} \(save_model writes about 6 per tree\)",
    )
    monkeypatch.setattr(persistence, "MAX_CENTRAL_DIRECTORY_BYTES", 100)
    refused(
        load_model,
        small_file,
        match=r"the archive's central directory is [\d,]+ bytes, above the limit of 100 bytes",
    )


def test_a_duplicate_member_is_refused(small_file, tmp_path):
    path = tmp_path / "twice.skops"
    with zipfile.ZipFile(small_file) as source, zipfile.ZipFile(path, "w") as archive:
        for name in source.namelist():
            archive.writestr(name, source.read(name))
        with pytest.warns(UserWarning, match="Duplicate name"):
            archive.writestr("schema.json", source.read("schema.json"))
    refused(load_model, path, match=r"twice\.skops: the archive holds member 'schema\.json' twice")


def _deep(levels: int) -> str:
    return "[" * levels + "]" * levels


SCHEMA_TEXTS = [
    pytest.param(
        "[1, 2, 3]",
        r"schema\.json: the top-level object: expected a JSON object, "
        r"found an array",
        id="a-list",
    ),
    pytest.param(
        "not json",
        r"schema\.json: the top-level object: expected JSON, found text "
        r"that is not \(JSONDecodeError: ",
        id="not-json",
    ),
    pytest.param(
        '{"a": ' + _deep(100_000) + "}",
        r"arrays and objects nested 100,001 deep, "
        r"above the limit of 64",
        id="very-deep-nesting",
    ),
    pytest.param("\udcff", r"expected JSON text, found bytes that are not", id="not-utf8"),
]


@pytest.mark.parametrize(("text", "message"), SCHEMA_TEXTS)
def test_a_malformed_schema_text_is_one_line(small_file, tmp_path, text, message):
    raw = text.encode("utf-8", "surrogateescape")
    path = rewrite(small_file, tmp_path / "bad.skops", members={"schema.json": raw})
    pattern = r"bad\.skops: schema\.json: .*" + message.removeprefix(r"schema\.json: ")
    refused(load_model, path, match=pattern)


def _edit_first(fields, change):
    def edit(state):
        change(next(nodes(state, **fields)))

    return edit


def _cycle(state):
    model = attribute(state, "model")
    classifier = attribute(model, "classifier_")
    classifier["__id__"] = state["__id__"]  # the root dictionary, inside itself


def _list_node(content: list, node_id: int) -> dict:
    """A skops schema node: a builtins list of the nodes ``content``."""
    return {
        "__class__": "list",
        "__module__": "builtins",
        "__loader__": "ListNode",
        "content": content,
        "__id__": node_id,
    }


def _chain(lists: int, refs: int):
    """A schema edit adding ``extra``: ``lists`` lists, each holding the one before ``refs``
    times (by __id__), the first holding the int 1."""
    first = {
        "__class__": "int",
        "__module__": "builtins",
        "__loader__": "JsonNode",
        "content": "1",
        "__id__": 1,
    }

    def edit(state):
        items = [first]
        for k in range(2, lists + 2):
            items.append(_list_node([{"__id__": k - 1}] * refs, k))
        state["content"]["extra"] = _list_node(items, 100)

    return edit


# 30 lists, each holding the one before twice (by __id__): 2^30 paths for skops' audit.
_shared_chain = _chain(30, 2)
# Objects shared by __id__ nest deeper than the JSON does: each list holds the one before.
_tall_chain = _chain(58, 1)


SCHEMA_EDITS = [
    pytest.param(
        lambda s: s.pop("protocol"),
        r"schema\.json: protocol: expected skops protocol "
        r"2 \(the one this skops writes and reads\), found none",
        id="no-protocol",
    ),
    pytest.param(
        lambda s: s.update(protocol="2"),
        r"protocol: expected skops protocol 2 .*, "
        r"found the string '2'",
        id="protocol-string",
    ),
    pytest.param(lambda s: s.update(protocol=2.0), r"found the value 2\.0", id="protocol-float"),
    pytest.param(lambda s: s.update(protocol=True), r"found the value True", id="protocol-bool"),
    pytest.param(lambda s: s.update(protocol=99), r"found the value 99", id="protocol-newer"),
    pytest.param(lambda s: s.update(protocol=1), r"found the value 1$", id="protocol-older"),
    pytest.param(lambda s: s.update(protocol=-1), r"found the value -1", id="protocol-negative"),
    pytest.param(
        lambda s: s.update(__loader__="EvilNode"),
        r"the top-level object: "
        r"__loader__: expected one of the skops loaders a model uses \(.*\), found the "
        r"string 'EvilNode'",
        id="unknown-loader",
    ),
    pytest.param(
        _edit_first({"__loader__": "TreeNode"}, lambda n: n.pop("__loader__")),
        r"model\.classifier_\.estimators_\[0\]\.tree_: __loader__: .*, found none",
        id="no-loader",
    ),
    pytest.param(
        _edit_first(
            {"__loader__": "ObjectNode"}, lambda n: n.update(__loader__="QuantileForestNode")
        ),
        r"found the string 'QuantileForestNode'",
        id="loader-reform-never-uses",
    ),
    pytest.param(
        _edit_first({"__loader__": "ObjectNode"}, lambda n: n.update(__class__=7)),
        r"model: __class__: expected a string, found the value 7",
        id="class-not-str",
    ),
    pytest.param(
        _edit_first({"__loader__": "DictNode"}, lambda n: n.update(content=[])),
        r"the top-level object: content: expected an object, found an array",
        id="dict-content-a-list",
    ),
    pytest.param(
        lambda s: s["content"].update(model=[1]),
        r"schema\.json: model: expected an "
        r"object \(a skops node\), found an array",
        id="node-a-list",
    ),
    pytest.param(
        _edit_first({"__loader__": "ListNode"}, lambda n: n.update(content="x")),
        r"content: expected an array, found the string 'x'",
        id="list-content-str",
    ),
    pytest.param(
        _edit_first({"__loader__": "NdArrayNode"}, lambda n: n.update(type="pickle")),
        r"type: expected 'numpy' or 'json', found the string 'pickle'",
        id="array-type",
    ),
    pytest.param(
        _edit_first({"__loader__": "NdArrayNode"}, lambda n: n.update(file="x.npy")),
        r"file: names 'x\.npy', which the archive does not hold",
        id="missing-member",
    ),
    pytest.param(
        _edit_first({"__loader__": "NdArrayNode"}, lambda n: n.update(file=["a"])),
        r"file: expected a string, found an array",
        id="member-name-a-list",
    ),
    pytest.param(
        _edit_first({"__loader__": "TreeNode"}, lambda n: n.pop("__reduce__")),
        r"tree_: __reduce__: expected an object, found none",
        id="tree-no-reduce",
    ),
    pytest.param(
        _edit_first({"__loader__": "JsonNode"}, lambda n: n.update(content=_deep(100_000))),
        r"content: expected a JSON number, string, true, false or null, found "
        r"'\[\[\[",
        id="json-content-deep",
    ),
    pytest.param(
        _edit_first({"__loader__": "JsonNode"}, lambda n: n.update(content="9" * 5000)),
        r"content: expected JSON, found '9999.*\(ValueError: Exceeds the limit",
        id="json-content-huge-int",
    ),
    pytest.param(
        _edit_first({"__loader__": "JsonNode"}, lambda n: n.update(content=3)),
        r"content: expected a string, found the value 3",
        id="json-content-not-str",
    ),
    pytest.param(
        _edit_first({"__loader__": "ObjectNode"}, lambda n: n.update(__id__=[1])),
        r"model: __id__: expected an integer, found an array",
        id="id-a-list",
    ),
    pytest.param(
        _edit_first({"__loader__": "ObjectNode"}, lambda n: n.update(__id__=1.5)),
        r"model: __id__: expected an integer, found the value 1\.5",
        id="id-a-float",
    ),
    pytest.param(
        _cycle,
        r"model\.classifier_: __id__ \d+ names an object that contains it "
        r"\(a cycle\)",
        id="cycle",
    ),
    pytest.param(
        _shared_chain, r"extra\[\d+\]: more than 500,000 objects to audit", id="shared-paths"
    ),
    pytest.param(
        _tall_chain,
        r"extra\[\d+\]: objects nested 33 deep \(through shared "
        r"__id__s\), above the limit of 32",
        id="shared-depth",
    ),
    pytest.param(
        _edit_first(
            {"__loader__": "ObjectNode"}, lambda n: n.update(__loader__="CachedNode", __id__=999)
        ),
        r"model: a reference \(CachedNode\) to an object the file does not define",
        id="cached-unknown",
    ),
    pytest.param(
        _edit_first(
            {"__loader__": "NdArrayNode"},
            lambda n: n.update(__loader__="SparseMatrixNode", type="scipy"),
        ),
        r"a scipy sparse matrix, which no REFORM model holds",
        id="sparse-matrix",
    ),
    pytest.param(
        _edit_first({"__loader__": "NdArrayNode"}, lambda n: n.update(file="schema.json")),
        r"array 'schema\.json': not a \.npy array \(ValueError: ",
        id="member-not-npy",
    ),
]


@pytest.mark.parametrize(("edit", "message"), SCHEMA_EDITS)
def test_a_malformed_schema_is_refused_in_one_line(small_file, trees_file, tmp_path, edit, message):
    source = trees_file if "tree" in message or "estimators_" in message else small_file
    path = rewrite(source, tmp_path / "bad.skops", schema=edit)
    for read in (load_model, model_info):
        refused(
            read,
            path,
            match=r"bad\.skops: schema\.json: .*" + message.removeprefix(r"schema\.json: "),
        )


def test_an_array_header_promising_more_than_its_member_is_refused(small_file, tmp_path):
    with zipfile.ZipFile(small_file) as archive:
        name = next(n for n in archive.namelist() if n.endswith(".npy"))
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, np.zeros(3))  # header, then 24 bytes of data
    data = buffer.getvalue().replace(b"(3,)", b"(1000000000000,)")
    path = rewrite(small_file, tmp_path / "lie.skops", members={name: data})
    refused(
        load_model,
        path,
        match=rf"array '{name}': its header promises shape "
        r"\(1000000000000,\) of float64 \(8,000,000,000,000 bytes\), the member "
        r"holds \d+",
    )


def test_one_member_read_by_many_objects_counts_each_time(tmp_path):
    source = save_model(fitted("weighted-knn"), tmp_path / "knn.skops")
    with zipfile.ZipFile(source) as archive:
        size, name = max(
            (info.file_size, info.filename)
            for info in archive.infolist()
            if info.filename.endswith(".npy")
        )  # the training pairs, _fit_X

    def edit(state):
        copies = [
            {
                "__class__": "ndarray",
                "__module__": "numpy",
                "__loader__": "NdArrayNode",
                "type": "numpy",
                "file": name,
                "__id__": 10 + k,
            }
            for k in range(20)
        ]
        state["content"]["extra"] = _list_node(copies, 9)

    path = rewrite(source, tmp_path / "many.skops", schema=edit)
    limit = path.stat().st_size + 5 * size  # the file fits, 20 more reads of one member do not
    refused(
        load_model,
        path,
        max_bytes=limit,
        match=r"extra\[\d+\]: the objects read archive members \(one "
        rf"per object\) of [\d,]+ bytes, above the limit of {limit:,} bytes",
    )


# The estimators' arrays: what scikit-learn's compiled predictors index without bounds checks.


def _tree_nodes(change):
    """A bagged-trees model whose first tree's node array is changed by ``change(nodes)``."""

    def make():
        model = fresh("bagged-trees")
        model.classifier_.estimators_[0] = _deep_tree()
        tree = model.classifier_.estimators_[0].tree_
        state = tree.__getstate__()
        state["nodes"] = state["nodes"].copy()
        change(state["nodes"])
        tree.__setstate__(state)
        return payload(model)

    return make


def _deep_tree():
    """A tree of many nodes (the toy scenes' trees have one split), fitted on noise."""
    rng = np.random.default_rng(0)
    return DecisionTreeClassifier(max_depth=6, random_state=0).fit(
        rng.normal(size=(300, 2)), rng.integers(0, 2, 300).astype(float)
    )


def _tree_values(change):
    def make():
        model = fresh("bagged-trees")
        tree = model.classifier_.estimators_[0].tree_
        state = tree.__getstate__()
        state["values"] = state["values"].copy()
        change(state["values"])
        tree.__setstate__(state)
        return payload(model)

    return make


def _set_field(field, k, value):
    def change(array):
        array[field][k] = value

    return change


def _parent_shares_child(nodes):
    # The last split's right child becomes the left child of an earlier split as well: a node
    # of two parents (the compiled table's walk would visit it twice, and its subtree as often).
    split = np.flatnonzero(nodes["left_child"] >= 0)
    last, other = split[-1], split[-2]
    assert nodes["right_child"][last] > other
    nodes["left_child"][other] = nodes["right_child"][last]


def _knn(change):
    def make():
        model = fresh("weighted-knn")
        change(model.classifier_.steps[-1][1])
        return payload(model)

    return make


def _knn_tree(position, change):
    def alter(knn):
        state = list(knn._tree.__getstate__())
        state[position] = state[position].copy()
        change(state[position])
        knn._tree.__setstate__(tuple(state))

    return _knn(alter)


def _logistic(change):
    def make():
        model = fresh("logistic-regression")
        change(model.classifier_)
        return payload(model)

    return make


def _setitem(array, index, value):
    array[index] = value


ARRAY_DEFECTS = [
    pytest.param(
        _tree_nodes(_set_field("left_child", 0, 1_000_000)),
        r"classifier_\.estimators_\[0\]\.tree_\.children_left/right\[0\]: 1000000 and \d+, "
        r"expected -1 and -1 \(a leaf\) or two nodes after 0 and below \d+ \(node_count\)",
        id="child-out-of-range",  # scikit-learn's apply segfaults
    ),
    pytest.param(
        _tree_nodes(_set_field("left_child", 0, 0)),
        r"tree_\.children_left/right\[0\]: 0 and \d+, expected -1 and -1",
        id="child-is-itself",  # scikit-learn's apply loops for ever
    ),
    pytest.param(
        _tree_nodes(_set_field("right_child", 0, -1)),
        r"tree_\.children_left/right\[0\]: \d+ and -1, expected -1 and -1",
        id="half-a-leaf",
    ),
    pytest.param(
        _tree_nodes(_parent_shares_child),
        r"tree_\.children_left/right: node \d+ is the child of [02] nodes, expected 1",
        id="child-of-two-parents",
    ),
    pytest.param(
        _tree_nodes(_set_field("feature", 0, 100_000_000_000)),
        r"estimators_\[0\]\.tree_\.feature\[0\]: 100000000000, expected a feature index in "
        r"\[0, 2\) at a split",
        id="feature-out-of-range",  # scikit-learn's apply segfaults
    ),
    pytest.param(
        _tree_nodes(_set_field("feature", 0, -3)),
        r"tree_\.feature\[0\]: -3, expected a feature index",
        id="feature-negative",
    ),
    pytest.param(
        _tree_nodes(_set_field("threshold", 0, np.nan)),
        r"tree_\.threshold\[0\]: nan, expected a finite number",
        id="threshold-nan",
    ),
    pytest.param(
        _tree_values(lambda v: _setitem(v, (0, 0, 0), np.inf)),
        r"tree_\.value: expected finite numbers, found inf at \[0, 0, 0\]",
        id="value-infinite",
    ),
    pytest.param(
        _tree_values(lambda v: _setitem(v, (1, 0, 1), -0.5)),
        r"tree_\.value: expected class weights >= 0, found -0\.5 at \[1, 0, 1\]",
        id="value-negative",
    ),
    pytest.param(
        lambda: payload(_bagging_features([np.array([0, 5])])),
        r"classifier_\.estimators_features_\[0\]: expected feature indices in \[0, 2\), found "
        r"\[0, 5\]",
        id="bagging-columns-out-of-range",
    ),
    pytest.param(
        lambda: payload(_bagging_features([np.array([0])])),
        r"classifier_\.estimators_\[0\]\.n_features_in_: expected an integer in \[1, 1\], "
        r"found 2",
        id="bagging-columns-disagree-with-tree",
    ),
    pytest.param(
        lambda: payload(_bagging_n_estimators(0)),
        r"classifier_: parameters not valid: InvalidParameterError: The 'n_estimators' "
        r"parameter of BaggingClassifier must be an int in the range \[1, inf\)\. Got 0",
        id="bagging-parameter",
    ),
    pytest.param(
        _knn_tree(1, lambda idx: _setitem(idx, 0, 10**9)),
        r"classifier_\.steps\[1\]\._tree\.idx_array: expected a permutation of the 3300 "
        r"samples, found 1000000000 at \[0\]",
        id="knn-index-out-of-range",
    ),
    pytest.param(
        _knn_tree(2, lambda nodes: _setitem(nodes, 1, (0, 10**6, 1, 0.5))),
        r"_tree\.node_data\[1\]: samples \[0, 1000000\), expected a range within \[0, 3300\]",
        id="knn-node-range",
    ),
    pytest.param(
        _knn_tree(2, lambda nodes: nodes["is_leaf"].__setitem__(slice(None), 0)),
        r"_tree\.node_data\[\d+\]: not a leaf, but its children \d+ and \d+ are beyond the \d+ "
        r"nodes",
        id="knn-node-without-children",
    ),
    pytest.param(
        _knn(
            lambda knn: setattr(
                knn, "_fit_X", np.where(np.arange(3300)[:, None] == 7, np.nan, knn._fit_X)
            )
        ),
        r"classifier_\.steps\[1\]\._fit_X: expected finite numbers, found nan at \[7, 0\]",
        id="knn-nan-sample",
    ),
    pytest.param(
        _knn(lambda knn: setattr(knn, "_fit_X", knn._fit_X[:, :1].copy())),
        r"steps\[1\]\._fit_X: expected shape \('any', 2\), found \(3300, 1\)",
        id="knn-samples-of-one-feature",
    ),
    pytest.param(
        _knn(lambda knn: setattr(knn, "n_neighbors", 5000)),
        r"steps\[1\]\.n_neighbors: expected an integer in \[1, 3300\], found 5000",
        id="knn-more-neighbours-than-samples",
    ),
    pytest.param(
        _knn(lambda knn: setattr(knn, "_y", knn._y + 2)),
        r"steps\[1\]\._y: expected class indices in \[0, 2\), found 3 at \[0\]|"
        r"steps\[1\]\._y: expected class indices in \[0, 2\), found 2 at \[0\]",
        id="knn-label-out-of-range",
    ),
    pytest.param(
        _logistic(lambda lr: setattr(lr.steps[1][1], "coef_", np.ones((1, 3)))),
        r"classifier_\.steps\[1\]\.coef_: expected shape \(1, 2\), found \(1, 3\)",
        id="logistic-coef-shape",
    ),
    pytest.param(
        _logistic(lambda lr: setattr(lr.steps[1][1], "intercept_", np.array([np.nan]))),
        r"steps\[1\]\.intercept_: expected finite numbers, found nan at \[0\]",
        id="logistic-intercept-nan",
    ),
    pytest.param(
        _logistic(lambda lr: setattr(lr.steps[0][1], "scale_", np.array([1.0, 0.0]))),
        r"classifier_\.steps\[0\]\.scale_: expected positive scales, found 0\.0 at \[1\]",
        id="scaler-zero-scale",
    ),
    pytest.param(
        _logistic(lambda lr: setattr(lr.steps[0][1], "mean_", np.array([np.inf, 0.0]))),
        r"steps\[0\]\.mean_: expected finite numbers, found inf at \[0\]",
        id="scaler-infinite-mean",
    ),
]


def _bagging_features(columns):
    model = fresh("bagged-trees")
    model.classifier_.estimators_features_[0] = columns[0]
    return model


def _bagging_n_estimators(n):
    model = fresh("bagged-trees")
    model.classifier_.n_estimators = n
    return model


@pytest.mark.parametrize(("make", "message"), ARRAY_DEFECTS)
def test_an_estimator_array_out_of_range_is_refused_at_load(make, message, tmp_path):
    path = tmp_path / "broken.skops"
    sio.dump(make(), path)
    for read in (load_model, model_info):
        pattern = r"broken\.skops: inconsistent model: (classifier_\S*)?" + message
        refused(read, path, match=pattern)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        pytest.param(
            {"threshold": 1.5},
            r"threshold must be None or a probability in \(0, 1\), "
            r"got 1\.5",
            id="threshold",
        ),
        pytest.param(
            {"reconstruction": "majority"},
            r"reconstruction must be one of .*, got "
            r"'majority'",
            id="reconstruction",
        ),
        pytest.param({"fast": "yes"}, r"fast must be True or False, got 'yes'", id="fast"),
    ],
)
def test_the_models_parameters_are_checked(change, message, tmp_path):
    model = fresh()
    vars(model).update(change)
    path = tmp_path / "params.skops"
    sio.dump(payload(model), path)
    refused(
        load_model,
        path,
        match=r"params\.skops: the model's parameters are not valid: " + message,
    )


def test_a_model_that_cannot_classify_is_refused_at_load(tmp_path):
    model = fresh()
    # A pipeline whose first step is no transformer: every array in range, no prediction.
    logistic = model.classifier_.steps[-1][1]
    model.classifier_.steps = [("logreg", logistic), ("again", logistic)]
    path = tmp_path / "no-transform.skops"
    sio.dump(payload(model), path)
    refused(
        load_model,
        path,
        match=r"no-transform\.skops: the model fails to classify a "
        r"frame of 4 people: AttributeError: .*transform",
    )


def test_a_stored_compiled_table_is_ignored(tmp_path):
    model = fresh()
    model._compiled = LogisticRegression()  # a file cannot choose what predict calls
    path = tmp_path / "compiled.skops"
    sio.dump(payload(model), path)
    loaded = load_model(path)
    assert not isinstance(loaded._compiled, LogisticRegression)
    frames = toy_frames(9, 5)
    assert loaded.predict(frames) == fresh().predict(frames)


def test_a_model_of_another_scikit_learn_is_one_line_without_warnings_first(tmp_path):
    """Every scikit-learn version in the file rewritten to 0.1.0: the version check refuses it,
    and scikit-learn's own warning, raised while the file's estimators are built, does not come
    first."""
    import warnings as _warnings
    import zipfile

    import sklearn

    model = Reform(make_classifier("logistic-regression")).fit(toy_frames(0, 10))
    path = save_model(model, tmp_path / "m.skops")
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    members["schema.json"] = members["schema.json"].replace(sklearn.__version__.encode(), b"0.1.0")
    old = tmp_path / "old.skops"
    with zipfile.ZipFile(old, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    with _warnings.catch_warnings(record=True) as caught:
        _warnings.simplefilter("always")
        refused(load_model, old, match=r"old.skops: model written with scikit-learn 0.1.0")
    assert [str(w.message) for w in caught] == []
