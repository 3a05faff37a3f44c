"""Saving and loading fitted REFORM models with skops: no pickle, no code run from a file.

A model file is a skops archive of one dictionary: the fitted :class:`reform.Reform` and, beside
it, what a reader wants to know without trusting the model first: the file format, the versions
of reform-sim and scikit-learn that wrote it, the features, the classifier and a summary of the
training data.

``load_model`` checks a file whole, in this order, and refuses it at the first problem with one
``ValueError`` line naming the file and what is wrong:

1. **The archive, before anything is inflated**: the file's size, the size of its central
   directory, the number of members, the total size they inflate to and the ratio of that to the
   file's size (a decompression bomb), their compression (stored or deflated) and their CRCs.
   Deflated members are inflated here, in bounded chunks, and handed to skops stored, because
   Python's ``zipfile`` inflates a whole member before it cuts it to the size its entry claims.
2. **The schema** (``schema.json``): JSON of bounded nesting, a JSON object, the skops protocol
   this skops writes, and every object in it one of the kinds skops writes, with the fields its
   loader reads, the archive members it names present and each ``.npy`` header consistent with its
   member's size; objects shared by ``__id__`` may not contain themselves, nor nest or repeat
   beyond the bounds skops' recursive reader can take.
3. **The types**: every type the file would build must be in a fixed allow-list (scikit-learn's
   own estimators are trusted by skops already), so a file from someone else cannot run code.
4. **The model**: written by this reform-sim, fitted, its parts in agreement (features, classes
   [0, 1], parameters), and every trusted estimator's internal arrays in range: a tree's child
   indices, feature indices and thresholds, a neighbour tree's index arrays, coefficients and
   scalers finite, shapes that agree. scikit-learn's compiled predictors index these arrays
   without bounds checks, so a model that passed (1)-(3) could still crash the process on first
   use. Last, the model classifies one small frame. A model that loads is a model that predicts.

skops is imported only inside these functions.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import struct
import warnings
import zipfile
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import sklearn
from sklearn.base import BaseEstimator, is_classifier
from sklearn.calibration import CalibratedClassifierCV, _CalibratedClassifier, _SigmoidCalibration
from sklearn.ensemble import BaggingClassifier, ExtraTreesClassifier, RandomForestClassifier
from sklearn.exceptions import InconsistentVersionWarning, NotFittedError
from sklearn.isotonic import IsotonicRegression
from sklearn.linear_model import LogisticRegression
from sklearn.neighbors import BallTree, KDTree, KNeighborsClassifier
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.tree import BaseDecisionTree
from sklearn.tree._tree import Tree
from sklearn.utils.validation import check_is_fitted

import reform
from reform.atomic import atomic_open
from reform.datasets.errors import shorten
from reform.detector import Reform, _check_threshold, check_calibration
from reform.features import check_features
from reform.frame import Frame
from reform.path_argument import path_argument
from reform.reconstruction import check_reconstruction

FORMAT = "reform-sim model"
FORMAT_VERSION = 1

# Types a REFORM model file may hold beyond what skops trusts by default: the detector itself and
# the compiled internals of scikit-learn's trees and neighbour searches.
TRUSTED_TYPES = (
    "reform.detector.Reform",
    "sklearn.calibration._CalibratedClassifier",  # Reform(calibration=...): one per fold
    "sklearn.calibration._SigmoidCalibration",
    "sklearn.model_selection._split.GroupKFold",  # the calibration's folds (n_splits only)
    "sklearn.tree._tree.Tree",
    "sklearn.neighbors._kd_tree.KDTree",
    "sklearn.neighbors._ball_tree.BallTree",
    "sklearn.metrics._dist_metrics.EuclideanDistance64",
    "sklearn.metrics._dist_metrics.ManhattanDistance64",
    "sklearn.metrics._dist_metrics.ChebyshevDistance64",
    "sklearn.metrics._dist_metrics.MinkowskiDistance64",
)

# Limits of a model file, checked before anything is inflated. REFORM's models are far below
# them: 30 bagged trees fitted on 3,300 pairs write 0.7 MB in 183 members; a KNN keeps about
# 50 bytes per training pair. The byte limit is load_model's ``max_bytes``.
MAX_MODEL_BYTES = 1 << 30  # bytes (1 GiB): largest file, and largest total its members inflate to
MAX_MODEL_MEMBERS = 10_000  # members of the zip archive (save_model writes about 6 per tree)
MAX_CENTRAL_DIRECTORY_BYTES = 4 << 20  # bytes (4 MiB): the archive's table of members (~70 each)
MAX_COMPRESSION_RATIO = 100  # inflated bytes per byte of file (deflate reaches 1032; bombs do)
RATIO_CHECKED_ABOVE_BYTES = 16 << 20  # bytes (16 MiB) inflated: below this, any ratio is harmless
MAX_SCHEMA_BYTES = 64 << 20  # bytes (64 MiB) of schema.json (30 bagged trees write 0.66 MB)
MAX_SCHEMA_NESTING = 64  # JSON arrays and objects nested in schema.json (REFORM's files: 22)
MAX_OBJECT_DEPTH = 32  # objects nested in one another as skops builds them (REFORM's files: 11)
MAX_SCHEMA_OBJECTS = 500_000  # objects skops visits to audit a file (a shared one once per use)

_MESSAGE_LIMIT = 300  # characters of an exception's text quoted in an error
_INFLATE_CHUNK_BYTES = 1 << 20  # bytes inflated at once while checking a deflated member
_END_OF_CENTRAL_DIRECTORY = struct.Struct("<4s4H2LH")  # the zip's last record (22 bytes)
_END_SIGNATURE = b"PK\x05\x06"
_ZIP64_LOCATOR_SIGNATURE = b"PK\x06\x07"
_ZIP64_LOCATOR_BYTES = 20
_MAX_ZIP_COMMENT_BYTES = 1 << 16

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "MAX_CENTRAL_DIRECTORY_BYTES",
    "MAX_COMPRESSION_RATIO",
    "MAX_MODEL_BYTES",
    "MAX_MODEL_MEMBERS",
    "MAX_OBJECT_DEPTH",
    "MAX_SCHEMA_BYTES",
    "MAX_SCHEMA_NESTING",
    "MAX_SCHEMA_OBJECTS",
    "RATIO_CHECKED_ABOVE_BYTES",
    "TRUSTED_TYPES",
    "load_model",
    "model_info",
    "save_model",
]


def _skops_io() -> Any:
    try:
        import skops.io as sio
    except ImportError as exc:  # pragma: no cover - skops is a dependency of the project
        raise ImportError(
            "saving REFORM models needs skops: pip install 'skops>=0.16,<0.17'"
        ) from exc
    return sio


def _versions() -> dict[str, str]:
    return {"reform_sim": reform.__version__, "scikit_learn": sklearn.__version__}


def save_model(model: Reform, path: str | os.PathLike[str]) -> Path:
    """Writes a fitted REFORM model to a skops file (atomically).

    Args:
        model: a fitted :class:`reform.Reform`.
        path: the file to write, conventionally ``*.skops``.

    Returns:
        The path written.

    Raises:
        TypeError: if ``model`` is not a Reform.
        sklearn.exceptions.NotFittedError: if it is not fitted.
    """

    if not isinstance(model, Reform):
        raise TypeError(f"model must be a reform.Reform, got {type(model).__name__}")
    path = path_argument(path, name="path", function="save_model")
    check_is_fitted(model, "classifier_")
    sio = _skops_io()
    payload = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "versions": _versions(),
        "features": list(model.features_),
        "classifier": type(model.classifier_).__name__,
        "classifier_repr": repr(model.classifier_),
        "reconstruction": model.reconstruction,
        "threshold": model.threshold,
        "training": model.training_summary_,
        "model": model,
    }
    if model.calibration is not None:  # absent at the default: a default file stays as it was
        payload["calibration"] = model.calibration
    data = sio.dumps(payload)
    with atomic_open(path, "wb") as handle:
        handle.write(data)
    return path


def load_model(
    path: str | os.PathLike[str],
    *,
    trusted: Iterable[str] = (),
    max_bytes: int = MAX_MODEL_BYTES,
) -> Reform:
    """Reads a REFORM model written by :func:`save_model`, checked whole (see the module notes).

    Args:
        path: the skops file.
        trusted: extra type names to trust (for a classifier of your own); by default only
            :data:`TRUSTED_TYPES` and skops' defaults.
        max_bytes: largest file to read, and largest total its members may inflate to, bytes.

    Returns:
        The fitted :class:`reform.Reform`, ready to predict.

    Raises:
        FileNotFoundError: if the file does not exist.
        ValueError: one line naming the file, if the path is a folder or unreadable, the file is
            above a size limit, is not a skops file or a malformed one (its archive or its
            ``schema.json``), holds types outside the trusted list, is not a REFORM model file,
            was written by another version of reform-sim or a scikit-learn of another minor
            version, or holds a Reform that is not fitted, whose parts disagree (features
            unknown, a classifier fitted on another number of features than ``features_``
            names, classes other than [0, 1]), whose estimators' arrays are out of range, or
            that cannot classify a frame.
    """
    path = path_argument(path, name="path", function="load_model")
    return _unwrap(path, _read_payload(path, trusted, max_bytes))


def model_info(
    path: str | os.PathLike[str],
    *,
    trusted: Iterable[str] = (),
    max_bytes: int = MAX_MODEL_BYTES,
) -> dict[str, Any]:
    """The metadata of a model file (versions, features, classifier, reconstruction, threshold,
    calibration, training summary).

    The file is checked as :func:`load_model` checks it, with the same arguments and errors.
    """
    path = path_argument(path, name="path", function="model_info")
    payload = _read_payload(path, trusted, max_bytes)
    model = _unwrap(path, payload)
    info = {key: value for key, value in payload.items() if key != "model"}
    info["calibration"] = model.calibration
    return info


def _read_payload(path: Path, trusted: Iterable[str], max_bytes: int) -> Any:
    if isinstance(max_bytes, bool) or not isinstance(max_bytes, int) or max_bytes < 1:
        raise ValueError(f"max_bytes must be a positive number of bytes, got {max_bytes!r}")
    data = _read(path, max_bytes)
    if data[:4] != b"PK\x03\x04" and b"reform-sim dante model" in data[8 : 8 + (1 << 20)]:
        raise ValueError(
            f"{path}: a DANTE model file (safetensors), not a REFORM model: use it with the "
            "detector dante (option model=FILE)"
        )
    data = _safe_archive(path, data, max_bytes)
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        _Schema(path, archive, max_bytes).check()
    untrusted = _check_types(path, data, trusted)
    try:
        with warnings.catch_warnings():
            # A model from another scikit-learn warns as it is built; _unwrap then refuses it
            # in one line naming both versions, so the warning would only come first.
            warnings.simplefilter("ignore", InconsistentVersionWarning)
            return _skops_io().loads(data, trusted=untrusted)
    except Exception as exc:  # skops and the constructors it calls, on a file's content
        raise ValueError(f"{path}: the file's objects cannot be built: {_describe(exc)}") from exc


def _describe(exc: BaseException) -> str:
    return shorten(f"{type(exc).__name__}: {exc}", _MESSAGE_LIMIT)


def _too_big(what: str, size: int, limit: int) -> str:
    return (
        f"{what} {size:,} bytes, above the limit of {limit:,} bytes; if you trust the file, "
        "raise it with max_bytes=... (load_model, model_info)"
    )


# --------------------------------------------------------------------------------------------
# The file and its archive, before anything is inflated


def _read(path: Path, max_bytes: int) -> bytes:
    if path.is_dir():
        raise ValueError(f"model file {path} is a folder: expected a skops file (*.skops)")
    if not path.exists():
        raise FileNotFoundError(f"model file {path} does not exist")
    if not path.is_file():
        raise ValueError(f"model file {path} is not a regular file: expected a skops file")
    try:
        with path.open("rb") as handle:
            size = os.fstat(handle.fileno()).st_size
            if size > max_bytes:
                raise ValueError(f"{path}: " + _too_big("the file is", size, max_bytes))
            data = handle.read(size)
            grew = handle.read(1)
    except OSError as exc:
        raise ValueError(f"model file {path} cannot be read: {exc.strerror or exc}") from exc
    if grew:
        raise ValueError(f"model file {path} changed while it was read; try again")
    return data


def _central_directory_bytes(path: Path, data: bytes) -> int:
    """The size of the archive's central directory, from its end record, found as ``zipfile``
    finds it (ZipFile reads the whole directory into ZipInfo objects before anything else)."""
    size = _END_OF_CENTRAL_DIRECTORY.size
    start = len(data) - size
    if start < 0 or data[start : start + 4] != _END_SIGNATURE or data[-2:] != b"\0\0":
        start = data.rfind(_END_SIGNATURE, max(0, len(data) - _MAX_ZIP_COMMENT_BYTES - size))
    if start < 0 or start + size > len(data):
        raise ValueError(f"{path}: not a skops model file (not a zip archive)")
    locator = start - _ZIP64_LOCATOR_BYTES
    if locator >= 0 and data[locator : locator + 4] == _ZIP64_LOCATOR_SIGNATURE:
        raise ValueError(
            f"{path}: not a skops model file written by save_model (a ZIP64 archive; model "
            "files stay below 4 GiB and 65,535 members)"
        )
    return _END_OF_CENTRAL_DIRECTORY.unpack_from(data, start)[5]


def _safe_archive(path: Path, data: bytes, max_bytes: int) -> bytes:
    """``data`` if its archive is within the limits and every member reads back whole; a
    deflated archive comes back rebuilt with stored members (see the module notes)."""
    directory = _central_directory_bytes(path, data)
    if directory > MAX_CENTRAL_DIRECTORY_BYTES:
        raise ValueError(
            f"{path}: the archive's central directory is {directory:,} bytes, above the limit "
            f"of {MAX_CENTRAL_DIRECTORY_BYTES:,} bytes (about {MAX_MODEL_MEMBERS:,} members)"
        )
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except Exception as exc:  # zipfile on hostile bytes: BadZipFile, ValueError, EOFError...
        raise ValueError(
            f"{path}: not a skops model file (not a readable zip archive: {_describe(exc)})"
        ) from exc
    with archive:
        members = archive.infolist()
        _check_members(path, data, members, max_bytes)
        stored = all(member.compress_type == zipfile.ZIP_STORED for member in members)
        contents = []
        for member in members:
            content = _inflate(path, archive, member)
            if not stored:
                contents.append(content)
    if stored:
        return data
    rebuilt = io.BytesIO()
    with zipfile.ZipFile(rebuilt, "w", compression=zipfile.ZIP_STORED) as plain:
        for member, content in zip(members, contents, strict=True):
            plain.writestr(member.filename, content)
    return rebuilt.getvalue()


def _check_members(path: Path, data: bytes, members: list[zipfile.ZipInfo], max_bytes: int) -> None:
    if len(members) > MAX_MODEL_MEMBERS:
        raise ValueError(
            f"{path}: the archive holds {len(members):,} members, above the limit of "
            f"{MAX_MODEL_MEMBERS:,} (save_model writes about 6 per tree)"
        )
    names: set[str] = set()
    for member in members:
        name = shorten(repr(member.filename))
        if member.filename in names:
            raise ValueError(f"{path}: the archive holds member {name} twice")
        names.add(member.filename)
        if member.flag_bits & 0x1:
            raise ValueError(f"{path}: archive member {name} is encrypted; model files are not")
        if member.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            raise ValueError(
                f"{path}: archive member {name} is compressed with method "
                f"{member.compress_type}; model files are stored (as save_model writes them) "
                "or deflated"
            )
        if member.compress_type == zipfile.ZIP_STORED and member.compress_size != member.file_size:
            raise ValueError(
                f"{path}: archive member {name} is stored in {member.compress_size:,} bytes but "
                f"its entry says {member.file_size:,}"
            )
    inflated = sum(member.file_size for member in members)
    if inflated > max_bytes:
        raise ValueError(
            f"{path}: " + _too_big("the archive's members inflate to", inflated, max_bytes)
        )
    if inflated > RATIO_CHECKED_ABOVE_BYTES and inflated > MAX_COMPRESSION_RATIO * len(data):
        raise ValueError(
            f"{path}: the archive's members inflate to {inflated:,} bytes from a file of "
            f"{len(data):,} ({inflated / len(data):,.0f} to 1, above the limit of "
            f"{MAX_COMPRESSION_RATIO} to 1): a decompression bomb, or a model to save again "
            "uncompressed with save_model"
        )
    if "schema.json" not in names:
        raise ValueError(f"{path}: not a skops model file (no schema.json inside)")
    schema = next(member for member in members if member.filename == "schema.json")
    if schema.file_size > MAX_SCHEMA_BYTES:
        raise ValueError(
            f"{path}: schema.json is {schema.file_size:,} bytes, above the limit of "
            f"{MAX_SCHEMA_BYTES:,} bytes (30 bagged trees write 0.66 MB)"
        )


def _inflate(path: Path, archive: zipfile.ZipFile, member: zipfile.ZipInfo) -> bytes:
    """A member's bytes, read in bounded chunks (its CRC checked), exactly as many as its entry
    says; a deflated stream holding more is read no further."""
    chunks = []
    total = 0
    try:
        with archive.open(member) as handle:
            while total < member.file_size:
                chunk = handle.read(min(_INFLATE_CHUNK_BYTES, member.file_size - total))
                if not chunk:
                    break
                chunks.append(chunk)
                total += len(chunk)
            handle.read(1)  # reaches the end of the member, where zipfile checks its CRC
    except Exception as exc:  # zipfile and zlib on hostile bytes
        raise ValueError(
            f"{path}: archive member {shorten(repr(member.filename))} is corrupt: {_describe(exc)}"
        ) from exc
    if total != member.file_size:
        raise ValueError(
            f"{path}: archive member {shorten(repr(member.filename))} holds {total:,} bytes, "
            f"its entry says {member.file_size:,}"
        )
    return b"".join(chunks)


# --------------------------------------------------------------------------------------------
# The schema: its shape checked before skops reads it

_JSON_STRING = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)


def _json_nesting(text: str) -> int:
    """Deepest nesting of arrays and objects in JSON text, strings skipped, without parsing it
    (Python's parser recurses once per level)."""
    skeleton = _JSON_STRING.sub("", text).encode("utf-8", "surrogatepass")
    codes = np.frombuffer(skeleton, dtype=np.uint8)
    opens = (codes == ord("[")) | (codes == ord("{"))
    closes = (codes == ord("]")) | (codes == ord("}"))
    depth = np.cumsum(opens.astype(np.int64) - closes.astype(np.int64))
    return int(depth.max(initial=0))


def _json_kind(value: Any) -> str:
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, str):
        return f"the string {shorten(repr(value))}"
    if value is None:
        return "null"
    return f"the value {shorten(repr(value))}"


def _child(where: str, key: str) -> str:
    """The location of ``key`` inside the object at ``where`` (attributes as ``a.b``)."""
    if key.isidentifier():
        return f"{where}.{key}" if where else key
    return f"{where}[{shorten(repr(key), 40)}]"


def _aside(where: str, what: str) -> str:
    """The location of a part of the object at ``where`` that is no attribute of it."""
    return f"{where or 'the top-level object'} ({what})"


class _Open:
    """An object of the schema whose children are being checked."""

    __slots__ = ("children", "height", "key", "next", "visits", "where")

    def __init__(self, key: int | None, where: str, children: list[tuple[str, Any]]) -> None:
        self.key = key
        self.where = where
        self.children = children
        self.next = 0
        self.height = 0  # of the tallest child
        self.visits = 0  # of all children

    def absorb(self, result: tuple[int, int]) -> None:
        self.height = max(self.height, result[0])
        self.visits += result[1]


class _Schema:
    """Checks ``schema.json`` as skops' reader will walk it, in its order (see the module notes).

    skops builds one node per object of the schema, depth first, remembering each by its
    ``__id__``: a later object with a known ``__id__`` is that node again, whatever else it
    says. Its type audit then walks every path of the node graph (a shared node once per
    parent) and its constructor recurses once per level, so the graph's height and its number of
    paths are bounded here, and an object containing itself (a cycle) is refused.
    """

    def __init__(self, path: Path, archive: zipfile.ZipFile, max_bytes: int) -> None:
        self.path = path
        self.archive = archive
        self.max_bytes = max_bytes
        self.members = {member.filename: member for member in archive.infolist()}
        self.memo: dict[int, tuple[int, int] | None] = {}  # None while open: (height, visits)
        self.arrays: set[str] = set()  # .npy members whose header was checked
        self.read_bytes = 0  # bytes of members the nodes will read (one per node)

    def fail(self, where: str, problem: str) -> NoReturn:
        place = shorten(where, 100) if where else "the top-level object"
        raise ValueError(f"{self.path}: schema.json: {place}: {problem}")

    def check(self) -> None:
        raw = self.archive.read("schema.json")
        try:
            text = raw.decode(json.detect_encoding(raw), "surrogatepass")
        except (UnicodeDecodeError, LookupError) as exc:
            self.fail("", f"expected JSON text, found bytes that are not ({_describe(exc)})")
        nesting = _json_nesting(text)
        if nesting > MAX_SCHEMA_NESTING:
            self.fail(
                "",
                f"arrays and objects nested {nesting:,} deep, above the limit of "
                f"{MAX_SCHEMA_NESTING} (REFORM's files nest 22 deep)",
            )
        try:
            schema = json.loads(text)
        except ValueError as exc:
            self.fail("", f"expected JSON, found text that is not ({_describe(exc)})")
        if not isinstance(schema, dict):
            self.fail("", f"expected a JSON object, found {_json_kind(schema)}")
        protocol = schema.get("protocol")
        _skops_io()  # skops, or its install command
        from skops.io._protocol import PROTOCOL

        if isinstance(protocol, bool) or protocol != PROTOCOL or not isinstance(protocol, int):
            found = "none" if "protocol" not in schema else _json_kind(protocol)
            self.fail(
                "protocol",
                f"expected skops protocol {PROTOCOL} (the one this skops writes and reads), "
                f"found {found}",
            )
        self.walk(schema)

    # The walk: depth first, children in skops' order, on an explicit stack.

    def walk(self, root: Any) -> None:
        stack: list[_Open] = []
        self.enter(root, "", stack)
        while stack:
            top = stack[-1]
            if top.next < len(top.children):
                where, child = top.children[top.next]
                top.next += 1
                result = self.enter(child, where, stack)
                if result is not None:
                    top.absorb(result)
                continue
            stack.pop()
            result = self.close(top.key, top.where, top.height + 1, top.visits + 1)
            if stack:
                stack[-1].absorb(result)

    def enter(self, state: Any, where: str, stack: list[_Open]) -> tuple[int, int] | None:
        """The (height, visits) of an object known or without children, else None (pushed)."""
        if not isinstance(state, dict):
            self.fail(where, f"expected an object (a skops node), found {_json_kind(state)}")
        key = state.get("__id__")
        if key is not None and (isinstance(key, bool) or not isinstance(key, int)):
            self.fail(where, f"__id__: expected an integer, found {_json_kind(key)}")
        if key is not None and key in self.memo:
            known = self.memo[key]
            if known is None:
                self.fail(where, f"__id__ {key} names an object that contains it (a cycle)")
            return known
        loader = state.get("__loader__")
        shape = _LOADERS.get(loader) if isinstance(loader, str) else None
        if shape is None:
            known_loaders = ", ".join(sorted(_LOADERS))
            self.fail(
                where,
                f"__loader__: expected one of the skops loaders a model uses ({known_loaders}), "
                f"found {'none' if '__loader__' not in state else _json_kind(loader)}",
            )
        for field in ("__class__", "__module__"):
            if not isinstance(state.get(field), str):
                self.fail(where, f"{field}: expected a string, found {self.kind(state, field)}")
        children = shape(self, state, where)
        key = key or None  # skops remembers objects by a non-zero __id__ only
        if not children:
            return self.close(key, where, 1, 1)
        if key is not None:
            self.memo[key] = None
        stack.append(_Open(key, where, children))
        return None

    def close(self, key: int | None, where: str, height: int, visits: int) -> tuple[int, int]:
        if height > MAX_OBJECT_DEPTH:
            self.fail(
                where,
                f"objects nested {height} deep (through shared __id__s), above the limit of "
                f"{MAX_OBJECT_DEPTH} (REFORM's files nest 11 deep)",
            )
        if visits > MAX_SCHEMA_OBJECTS:
            self.fail(
                where,
                f"more than {MAX_SCHEMA_OBJECTS:,} objects to audit (a shared object counts once "
                "for each object holding it)",
            )
        if key is not None:
            self.memo[key] = (height, visits)
        return height, visits

    # Fields.

    @staticmethod
    def kind(state: dict[str, Any], field: str) -> str:
        return "none" if field not in state else _json_kind(state[field])

    def field(self, state: dict[str, Any], where: str, field: str, kind: type) -> Any:
        value = state.get(field)
        if not isinstance(value, kind) or isinstance(value, bool):
            expected = {dict: "an object", list: "an array", str: "a string"}[kind]
            self.fail(where, f"{field}: expected {expected}, found {self.kind(state, field)}")
        return value

    def node(self, state: dict[str, Any], where: str, field: str) -> list[tuple[str, Any]]:
        return [(where, self.field(state, where, field, dict))]

    def items(self, state: dict[str, Any], where: str, field: str) -> list[tuple[str, Any]]:
        return [
            (f"{where}[{k}]", item) for k, item in enumerate(self.field(state, where, field, list))
        ]

    def parts(self, state: dict[str, Any], where: str, *names: str) -> list[tuple[str, Any]]:
        content = self.field(state, where, "content", dict)
        out = []
        for name in names:
            if not isinstance(content.get(name), dict):
                self.fail(
                    where, f"content.{name}: expected an object, found {self.kind(content, name)}"
                )
            out.append((_child(where, name), content[name]))
        return out

    def member(self, state: dict[str, Any], where: str) -> zipfile.ZipInfo:
        name = self.field(state, where, "file", str)
        member = self.members.get(name)
        if member is None:
            self.fail(where, f"file: names {shorten(repr(name))}, which the archive does not hold")
        self.read_bytes += member.file_size
        if self.read_bytes > self.max_bytes:
            self.fail(
                where,
                _too_big(
                    "the objects read archive members (one per object) of",
                    self.read_bytes,
                    self.max_bytes,
                ),
            )
        return member

    # One method per skops loader: checks the fields it reads and lists its children.

    def leaf(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        return []

    def json_value(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        content = self.field(state, where, "content", str)
        if content.lstrip()[:1] in ("[", "{"):
            self.fail(
                where,
                "content: expected a JSON number, string, true, false or null, "
                f"found {shorten(repr(content))}",
            )
        try:
            json.loads(content)
        except ValueError as exc:
            self.fail(
                where, f"content: expected JSON, found {shorten(repr(content))} ({_describe(exc)})"
            )
        return []

    def mapping(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        key_types = self.field(state, where, "key_types", dict)
        content = self.field(state, where, "content", dict)
        return [(_aside(where, "key types"), key_types)] + [
            (_child(where, key), value) for key, value in content.items()
        ]

    def sequence(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        return self.items(state, where, "content")

    def optional_content(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        if state.get("content") is None:
            return []
        return self.node(state, where, "content")

    def content(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        return self.node(state, where, "content")

    def reduced(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        reduce = self.field(state, where, "__reduce__", dict)
        if not isinstance(reduce.get("args"), dict):
            self.fail(
                where, f"__reduce__.args: expected an object, found {self.kind(reduce, 'args')}"
            )
        return [*self.node(state, where, "content"), (_aside(where, "arguments"), reduce["args"])]

    def array(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        kind = state.get("type")
        if kind == "numpy":
            self.npy(where, self.member(state, where))
            return []
        if kind == "json":
            return [
                *self.items(state, where, "content"),
                (f"{where}.shape", self.field(state, where, "shape", dict)),
            ]
        self.fail(where, f"type: expected 'numpy' or 'json', found {self.kind(state, 'type')}")

    def raw_bytes(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        self.member(state, where)
        return []

    def method(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        content = self.field(state, where, "content", dict)
        if not isinstance(content.get("func"), str):
            self.fail(where, f"content.func: expected a string, found {self.kind(content, 'func')}")
        return self.parts(state, where, "obj")

    def operator(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        return self.node(state, where, "attrs")

    def slice(self, state: dict[str, Any], where: str) -> list[tuple[str, Any]]:
        content = self.field(state, where, "content", dict)
        for name in ("start", "stop", "step"):
            value = content.get(name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
                self.fail(
                    where,
                    f"content.{name}: expected an integer or null, found "
                    f"{self.kind(content, name)}",
                )
        return []

    def cached(self, state: dict[str, Any], where: str) -> NoReturn:
        self.fail(where, "a reference (CachedNode) to an object the file does not define before")

    def sparse(self, state: dict[str, Any], where: str) -> NoReturn:
        self.fail(
            where,
            "a scipy sparse matrix, which no REFORM model holds (its .npz would be "
            "a second archive to inflate)",
        )

    def npy(self, where: str, member: zipfile.ZipInfo) -> None:
        """The member is a .npy array whose header promises exactly the bytes it holds, so that
        numpy allocates no more than the file gives."""
        if member.filename in self.arrays:
            return
        name = shorten(repr(member.filename))
        readers = {
            (1, 0): np.lib.format.read_array_header_1_0,
            (2, 0): np.lib.format.read_array_header_2_0,
        }
        try:
            with self.archive.open(member) as handle:
                version = np.lib.format.read_magic(handle)
                header = readers[version](handle) if version in readers else None
                offset = handle.tell()
        except Exception as exc:  # numpy's header parser on hostile bytes
            self.fail(where, f"array {name}: not a .npy array ({_describe(exc)})")
        if header is None:
            self.fail(where, f"array {name}: .npy format version {version}, expected 1.0 or 2.0")
        shape, _, dtype = header
        if dtype.hasobject:
            self.fail(where, f"array {name}: an array of Python objects, which needs pickle")
        count = math.prod(shape)
        if count and dtype.itemsize == 0:
            self.fail(where, f"array {name}: {count:,} elements of zero bytes")
        if offset + count * dtype.itemsize != member.file_size:
            self.fail(
                where,
                f"array {name}: its header promises shape {shorten(str(shape), 60)} of "
                f"{shorten(str(dtype), 60)} ({count * dtype.itemsize:,} bytes), the member "
                f"holds {member.file_size - offset:,}",
            )
        self.arrays.add(member.filename)


# skops' loaders (skops 0.16, protocol 2) and what each reads. QuantileForestNode (a package
# REFORM does not use) and SparseMatrixNode are refused.
_LOADERS: dict[str, Callable[[_Schema, dict[str, Any], str], list[tuple[str, Any]]]] = {
    "BytearrayNode": _Schema.raw_bytes,
    "BytesNode": _Schema.raw_bytes,
    "CachedNode": _Schema.cached,
    "ConstructorFromReduceNode": _Schema.content,
    "DTypeNode": _Schema.content,
    "DefaultDictNode": lambda self, state, where: self.parts(
        state, where, "main", "default_factory"
    ),
    "DictNode": _Schema.mapping,
    "FunctionNode": _Schema.leaf,
    "JsonNode": _Schema.json_value,
    "ListNode": _Schema.sequence,
    "LossNode": _Schema.reduced,
    "MaskedArrayNode": lambda self, state, where: self.parts(state, where, "data", "mask"),
    "MethodNode": _Schema.method,
    "NdArrayNode": _Schema.array,
    "ObjectNode": _Schema.optional_content,
    "OperatorFuncNode": _Schema.operator,
    "PartialNode": lambda self, state, where: self.parts(
        state, where, "func", "args", "kwds", "namespace"
    ),
    "RandomGeneratorNode": lambda self, state, where: self.parts(
        state, where, "bit_generator", "seed_seq"
    ),
    "RandomStateNode": _Schema.content,
    "SetNode": _Schema.sequence,
    "SliceNode": _Schema.slice,
    "SparseMatrixNode": _Schema.sparse,
    "TreeNode": _Schema.reduced,
    "TupleNode": _Schema.sequence,
    "TypeNode": _Schema.leaf,
}


def _check_types(path: Path, data: bytes, trusted: Iterable[str]) -> list[str]:
    sio = _skops_io()
    try:
        untrusted = sio.get_untrusted_types(data=data)
    except Exception as exc:  # skops on a file's content
        raise ValueError(f"{path}: not a readable skops model file: {_describe(exc)}") from exc
    allowed = set(TRUSTED_TYPES) | set(trusted)
    foreign = sorted(set(untrusted) - allowed)
    if foreign:
        raise ValueError(
            f"{path}: refusing to load: the file holds types outside the trusted list: "
            f"{shorten(str(foreign), 400)} (a REFORM model holds only scikit-learn and reform "
            "types). If you know where the file comes from and trust it, pass trusted=[...] "
            "naming these types."
        )
    return list(untrusted)


# --------------------------------------------------------------------------------------------
# The model


def _unwrap(path: Path, payload: Any) -> Reform:
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ValueError(f"{path}: not a REFORM model file (expected format {FORMAT!r})")
    if payload.get("format_version") != FORMAT_VERSION:
        raise ValueError(
            f"{path}: model file format version {shorten(repr(payload.get('format_version')))}, "
            f"this reform-sim reads version {FORMAT_VERSION}"
        )
    versions = payload.get("versions")
    versions = versions if isinstance(versions, dict) else {}
    current = _versions()
    written = shorten(str(versions.get("reform_sim")))
    if written != current["reform_sim"]:
        raise ValueError(
            f"{path}: model written by reform-sim {written}, this is reform-sim "
            f"{current['reform_sim']}; retrain it with `reform-sim train` (or install {written})"
        )
    written_sklearn = shorten(str(versions.get("scikit_learn", "")))
    if written_sklearn.split(".")[:2] != current["scikit_learn"].split(".")[:2]:
        raise ValueError(
            f"{path}: model written with scikit-learn {written_sklearn}, this is scikit-learn "
            f"{current['scikit_learn']}; retrain it with `reform-sim train`"
        )
    model = payload.get("model")
    if not isinstance(model, Reform):
        raise ValueError(
            f"{path}: the file's model is a {type(model).__name__}, not a reform.Reform"
        )
    model._compiled = None  # derived from classifier_, never read from a file
    _check_model(path, model, payload.get("features"))
    return model


def _check_model(path: Path, model: Reform, listed: Any) -> None:
    """Refuses a Reform that is not fitted, whose parts disagree or whose arrays are out of
    range, naming the file: such a model would load and then fail on first use, far from its
    file, or crash the process inside scikit-learn's compiled code.

    The objects came from a file, built without their constructors: scikit-learn's own
    inspection of them (tags, properties) may raise anything, which is refused as well.
    """

    missing = [name for name in ("classifier_", "features_") if not hasattr(model, name)]
    if missing:
        raise ValueError(
            f"{path}: expected a fitted reform.Reform, found an unfitted one (no "
            f"{' or '.join(missing)}); save a model after fit, e.g. with `reform-sim train`"
        )
    try:
        features = check_features(model.features_)
    except Exception as exc:  # features_ from a file: anything
        raise ValueError(
            f"{path}: the model's features_ are not valid: {shorten(str(exc), 400)}"
        ) from exc
    if listed is not None and (not isinstance(listed, list) or listed != list(features)):
        raise ValueError(
            f"{path}: the file lists features {shorten(repr(listed))}, expected the model's own "
            f"features_ {list(features)}"
        )
    classifier = model.classifier_
    name = type(classifier).__name__
    try:
        check_is_fitted(classifier)
    except (NotFittedError, TypeError) as exc:
        raise ValueError(
            f"{path}: expected a fitted pair classifier in the model, found an unfitted {name}"
        ) from exc
    except Exception as exc:  # scikit-learn's tags of an object missing its attributes
        raise ValueError(
            f"{path}: inconsistent model: a {name} that scikit-learn cannot inspect "
            f"({_describe(exc)})"
        ) from exc
    n_in = _attribute(classifier, "n_features_in_")
    if n_in is not None and (
        isinstance(n_in, bool) or not isinstance(n_in, (int, np.integer)) or n_in != len(features)
    ):
        raise ValueError(
            f"{path}: inconsistent model: features_ {list(features)} gives {len(features)} "
            f"feature(s) per pair, expected the classifier to take as many, found a {name} "
            f"fitted on {shorten(repr(n_in))} (n_features_in_)"
        )
    classes = _attribute(classifier, "classes_")
    found = classes.tolist() if isinstance(classes, np.ndarray) else classes
    if not isinstance(classes, np.ndarray) or found != [0, 1]:
        raise ValueError(
            f"{path}: inconsistent model: expected a pair classifier of classes [0, 1] "
            f"(apart, together), found a {name} with classes_ {shorten(repr(found))}"
        )
    try:
        check_reconstruction(getattr(model, "reconstruction", None))
        _check_threshold(getattr(model, "threshold", None), classifier)
        calibration = check_calibration(getattr(model, "calibration", None))
        calibrated = isinstance(classifier, CalibratedClassifierCV)
        if calibrated != (calibration is not None) or (
            calibrated and classifier.method != calibration
        ):
            found = classifier.method if calibrated else "none"
            raise ValueError(
                f"calibration {calibration!r} disagrees with the classifier's ({found!r})"
            )
        if not isinstance(getattr(model, "fast", None), bool):
            raise ValueError(f"fast must be True or False, got {getattr(model, 'fast', None)!r}")
    except Exception as exc:  # _check_threshold asks the classifier for predict_proba
        raise ValueError(
            f"{path}: the model's parameters are not valid: {shorten(str(exc), 400)}"
        ) from exc
    try:
        _check_estimator("classifier_", classifier, len(features))
    except _Broken as exc:
        raise ValueError(f"{path}: inconsistent model: {exc}") from None
    except Exception as exc:  # an attribute missing or of a type the checks cannot read
        raise ValueError(
            f"{path}: inconsistent model: classifier_ cannot be inspected: {_describe(exc)}"
        ) from exc
    try:
        model.predict([_probe_frame()])
    except Exception as exc:  # whatever the classifier raises
        raise ValueError(
            f"{path}: the model fails to classify a frame of 4 people: {_describe(exc)}"
        ) from exc


def _attribute(estimator: Any, name: str) -> Any:
    """``estimator.name``, or None when reading it fails (a property of a broken estimator)."""
    try:
        return getattr(estimator, name, None)
    except Exception:
        return None


def _probe_frame() -> Frame:
    """Four people on a square, facing its centre (one a robot), with heads: every feature."""
    position = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    yaw = np.arctan2(0.5 - position[:, 1], 0.5 - position[:, 0])
    return Frame(
        ids=np.arange(1, 5),
        position=position,
        yaw=yaw,
        kinds=("human", "human", "human", "robot"),
        head_position=position.copy(),
        head_yaw=yaw.copy(),
    )


# --------------------------------------------------------------------------------------------
# The estimators' internal arrays


class _Broken(Exception):
    """An estimator's attribute out of range: ``where`` names it from ``classifier_`` down."""

    def __init__(self, where: str, problem: str) -> None:
        super().__init__(f"{shorten(where, 160)}: {problem}")


def _array(
    where: str, value: Any, *, ndim: int, kind: str, shape: tuple | None = None, finite: bool = True
) -> np.ndarray:
    """``value`` as an ndarray of ``ndim`` dimensions, of numbers of ``kind`` (numpy kind codes,
    e.g. ``"iu"``, ``"fiu"``), of ``shape`` where its entries are not None, finite."""
    if not isinstance(value, np.ndarray):
        raise _Broken(where, f"expected an array, found a {type(value).__name__}")
    if value.dtype.kind not in kind or value.ndim != ndim:
        raise _Broken(
            where,
            f"expected a {ndim}-d array of {_KINDS[kind]}, found {value.ndim}-d "
            f"{shorten(str(value.dtype), 60)}",
        )
    if shape is not None and any(
        expected is not None and size != expected
        for size, expected in zip(value.shape, shape, strict=True)
    ):
        wanted = tuple("any" if expected is None else expected for expected in shape)
        raise _Broken(where, f"expected shape {wanted}, found {value.shape}")
    if finite and value.dtype.kind == "f" and not np.all(np.isfinite(value)):
        first = tuple(int(i) for i in np.argwhere(~np.isfinite(value))[0])
        raise _Broken(where, f"expected finite numbers, found {value[first]} at {list(first)}")
    return value


_KINDS = {"iu": "integers", "fiu": "numbers", "f": "floats", "fiub": "numbers"}


def _int(where: str, value: Any, *, low: int, high: int | None = None) -> int:
    """``value`` as an int in [low, high]."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise _Broken(where, f"expected an integer, found {shorten(repr(value))}")
    if value < low or (high is not None and value > high):
        bounds = f"at least {low}" if high is None else f"in [{low}, {high}]"
        raise _Broken(where, f"expected an integer {bounds}, found {value}")
    return int(value)


def _first(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def _check_estimator(where: str, estimator: Any, n_features: int | None) -> None:
    """Checks an estimator given ``n_features`` columns (None: unknown), and what it holds."""

    if not isinstance(estimator, BaseEstimator):
        _check_inside(where, estimator, n_features, depth=0, seen=set())
        return
    try:
        estimator._validate_params()  # scikit-learn's own parameter constraints
    except Exception as exc:
        raise _Broken(where, f"parameters not valid: {_describe(exc)}") from None
    if isinstance(estimator, Pipeline):
        _check_pipeline(where, estimator, n_features)
        return
    if isinstance(estimator, BaseDecisionTree):
        _check_decision_tree(where, estimator, n_features)
    elif isinstance(estimator, BaggingClassifier):
        _check_bagging(where, estimator, n_features)
    elif isinstance(estimator, (RandomForestClassifier, ExtraTreesClassifier)):
        _check_forest(where, estimator, n_features)
    elif isinstance(estimator, LogisticRegression):
        _check_logistic(where, estimator, n_features)
    elif isinstance(estimator, KNeighborsClassifier):
        _check_neighbors(where, estimator, n_features)
    elif isinstance(estimator, StandardScaler):
        _check_scaler(where, estimator, n_features)
    elif isinstance(estimator, CalibratedClassifierCV):
        _check_calibrated(where, estimator, n_features)
    else:  # another estimator: the trees it holds, wherever they sit
        if hasattr(estimator, "n_features_in_") and n_features is not None:
            _n_in(where, estimator, n_features)
        _check_inside(where, vars(estimator), n_features, depth=0, seen=set())


def _n_in(where: str, estimator: Any, n_features: int | None) -> int:
    return _int(
        f"{where}.n_features_in_",
        getattr(estimator, "n_features_in_", None),
        low=1 if n_features is None else n_features,
        high=n_features,
    )


def _classes(where: str, estimator: Any) -> np.ndarray:
    classes = _array(f"{where}.classes_", getattr(estimator, "classes_", None), ndim=1, kind="fiub")
    if classes.size < 1:
        raise _Broken(f"{where}.classes_", "expected at least one class, found none")
    return classes


def _n_classes(where: str, estimator: Any, classes: np.ndarray) -> int:
    """The estimator's ``n_classes_``, which must count its ``classes``."""
    return _int(
        f"{where}.n_classes_",
        getattr(estimator, "n_classes_", None),
        low=classes.size,
        high=classes.size,
    )


def _check_pipeline(where: str, pipeline: Any, n_features: int | None) -> None:
    steps = pipeline.steps
    if not isinstance(steps, list) or not steps:
        raise _Broken(f"{where}.steps", f"expected a list of steps, found {shorten(repr(steps))}")
    n = n_features
    for k, step in enumerate(steps):
        if not (isinstance(step, tuple) and len(step) == 2 and isinstance(step[0], str)):
            raise _Broken(f"{where}.steps[{k}]", "expected a (name, estimator) pair")
        estimator = step[1]
        if estimator is None or isinstance(estimator, str):
            continue
        _check_estimator(f"{where}.steps[{k}]", estimator, n)
        if not isinstance(estimator, StandardScaler):
            n = None  # another transformer: its output's width is its own


def _check_scaler(where: str, scaler: Any, n_features: int | None) -> None:
    n = _n_in(where, scaler, n_features)
    for name, needed in (("mean_", scaler.with_mean), ("scale_", scaler.with_std), ("var_", False)):
        value = getattr(scaler, name, None)
        if value is None and not needed:
            continue
        array = _array(f"{where}.{name}", value, ndim=1, kind="f", shape=(n,))
        if name == "scale_" and np.any(array <= 0):
            k = _first(array <= 0)
            raise _Broken(f"{where}.scale_", f"expected positive scales, found {array[k]} at [{k}]")


def _check_logistic(where: str, model: Any, n_features: int | None) -> None:
    n = _n_in(where, model, n_features)
    classes = _classes(where, model)
    rows = 1 if classes.size == 2 else classes.size
    _array(f"{where}.coef_", getattr(model, "coef_", None), ndim=2, kind="f", shape=(rows, n))
    _array(
        f"{where}.intercept_", getattr(model, "intercept_", None), ndim=1, kind="f", shape=(rows,)
    )


def _check_neighbors(where: str, model: Any, n_features: int | None) -> None:
    n = _n_in(where, model, n_features)
    fit_x = _array(
        f"{where}._fit_X", getattr(model, "_fit_X", None), ndim=2, kind="f", shape=(None, n)
    )
    n_samples = fit_x.shape[0]
    _int(
        f"{where}.n_samples_fit_",
        getattr(model, "n_samples_fit_", None),
        low=max(1, n_samples),
        high=n_samples,
    )
    _int(f"{where}.n_neighbors", model.n_neighbors, low=1, high=n_samples)
    if getattr(model, "outputs_2d_", None) is not False:
        raise _Broken(
            f"{where}.outputs_2d_",
            "expected False (one output: together or not), "
            f"found {shorten(repr(getattr(model, 'outputs_2d_', None)))}",
        )
    classes = _classes(where, model)
    labels = _array(
        f"{where}._y", getattr(model, "_y", None), ndim=1, kind="iu", shape=(n_samples,)
    )
    if labels.size and (labels.min() < 0 or labels.max() >= classes.size):
        k = _first((labels < 0) | (labels >= classes.size))
        raise _Broken(
            f"{where}._y",
            f"expected class indices in [0, {classes.size}), found {labels[k]} at [{k}]",
        )
    method = getattr(model, "_fit_method", None)
    if method == "brute":
        return
    expected = (
        {"kd_tree": KDTree, "ball_tree": BallTree}.get(method) if isinstance(method, str) else None
    )
    if expected is None:
        raise _Broken(
            f"{where}._fit_method",
            f"expected 'brute', 'kd_tree' or 'ball_tree', found {shorten(repr(method))}",
        )
    tree = getattr(model, "_tree", None)
    if type(tree) is not expected:
        raise _Broken(
            f"{where}._tree",
            f"expected a {expected.__name__} for _fit_method "
            f"{method!r}, found a {type(tree).__name__}",
        )
    _check_binary_tree(f"{where}._tree", tree, fit_x.shape)


def _check_binary_tree(where: str, tree: Any, shape: tuple[int, int] | None) -> None:
    """A KDTree or BallTree: its queries index ``data`` through ``idx_array`` and walk
    ``node_data`` as an implicit binary tree (children of node i: 2i + 1, 2i + 2)."""

    data, index, nodes, bounds = tree.get_arrays()
    data = _array(f"{where}.data", data, ndim=2, kind="f", shape=shape)
    n_samples, n_features = data.shape
    index = _array(f"{where}.idx_array", index, ndim=1, kind="iu", shape=(n_samples,))
    if np.any(np.bincount(np.clip(index, 0, n_samples), minlength=n_samples + 1)[:n_samples] != 1):
        outside = (index < 0) | (index >= n_samples)
        k = _first(outside) if outside.any() else None
        found = f"{index[k]} at [{k}]" if k is not None else "a repeated index"
        raise _Broken(
            f"{where}.idx_array",
            f"expected a permutation of the {n_samples} samples, found {found}",
        )
    fields = ("idx_start", "idx_end", "is_leaf", "radius")
    if not isinstance(nodes, np.ndarray) or nodes.ndim != 1 or nodes.dtype.names != fields:
        raise _Broken(f"{where}.node_data", f"expected a 1-d array of fields {fields}")
    n_nodes = nodes.size
    if n_nodes < 1:
        raise _Broken(f"{where}.node_data", "expected at least one node, found none")
    start, end = nodes["idx_start"], nodes["idx_end"]
    wrong = (start < 0) | (start > end) | (end > n_samples)
    if wrong.any():
        k = _first(wrong)
        raise _Broken(
            f"{where}.node_data[{k}]",
            f"samples [{start[k]}, {end[k]}), expected a range within [0, {n_samples}]",
        )
    inner = nodes["is_leaf"] == 0
    childless = inner & (2 * np.arange(n_nodes) + 2 >= n_nodes)
    if childless.any():
        k = _first(childless)
        raise _Broken(
            f"{where}.node_data[{k}]",
            f"not a leaf, but its children {2 * k + 1} and "
            f"{2 * k + 2} are beyond the {n_nodes} nodes",
        )
    radius = nodes["radius"]
    if not np.all(np.isfinite(radius) & (radius >= 0)):
        k = _first(~(np.isfinite(radius) & (radius >= 0)))
        raise _Broken(f"{where}.node_data[{k}]", f"radius {radius[k]}, expected a finite distance")
    rows = 2 if isinstance(tree, KDTree) else 1
    _array(f"{where}.node_bounds", bounds, ndim=3, kind="f", shape=(rows, n_nodes, n_features))
    metric = tree.__getstate__()[11]
    if type(metric).__name__ == "MinkowskiDistance64":
        p, weights, _ = metric.__getstate__()
        if not (isinstance(p, float) and math.isfinite(p) and p >= 1):
            raise _Broken(f"{where}.dist_metric.p", f"expected a finite p >= 1, found {p!r}")
        _array(
            f"{where}.dist_metric.w",
            weights,
            ndim=1,
            kind="f",
            shape=(n_features if weights.size else 0,),
        )
    weight = tree.sample_weight
    if weight is not None:
        _array(f"{where}.sample_weight", weight, ndim=1, kind="f", shape=(n_samples,))


def _check_decision_tree(where: str, model: Any, n_features: int | None) -> None:
    n = _n_in(where, model, n_features)
    outputs = _int(f"{where}.n_outputs_", getattr(model, "n_outputs_", None), low=1, high=1)
    n_classes = None
    if is_classifier(model):
        classes = _classes(where, model)
        n_classes = _n_classes(where, model, classes)
    tree = getattr(model, "tree_", None)
    if type(tree) is not Tree:
        raise _Broken(f"{where}.tree_", f"expected a Tree, found a {type(tree).__name__}")
    _check_tree(
        f"{where}.tree_",
        tree,
        n_features=n,
        n_outputs=outputs,
        n_classes=[1] if n_classes is None else [n_classes],
    )


def _check_tree(
    where: str,
    tree: Any,
    *,
    n_features: int | None,
    n_outputs: int | None,
    n_classes: list[int] | None,
) -> None:
    """A scikit-learn Tree as its builder makes it: nodes numbered parent before child, each
    node but the root the child of exactly one, leaves with both children -1; split features
    below the feature count; finite thresholds; one row of values per node."""
    count = tree.node_count
    if count < 1 or count != tree.capacity:
        raise _Broken(
            f"{where}.node_count", f"{count}, expected the {tree.capacity} nodes the tree holds"
        )
    _int(
        f"{where}.n_features",
        tree.n_features,
        low=1 if n_features is None else n_features,
        high=n_features,
    )
    _int(
        f"{where}.n_outputs",
        tree.n_outputs,
        low=1 if n_outputs is None else n_outputs,
        high=n_outputs,
    )
    found_classes = np.asarray(tree.n_classes).tolist()
    if n_classes is not None and found_classes != n_classes:
        raise _Broken(f"{where}.n_classes", f"expected {n_classes}, found {found_classes}")
    left, right = tree.children_left, tree.children_right
    node = np.arange(count)
    leaf = (left == -1) & (right == -1)
    split = (left > node) & (right > node) & (left < count) & (right < count) & (left != right)
    if not np.all(leaf | split):
        k = _first(~(leaf | split))
        raise _Broken(
            f"{where}.children_left/right[{k}]",
            f"{left[k]} and {right[k]}, expected -1 and -1 (a leaf) or two nodes after {k} and "
            f"below {count} (node_count)",
        )
    parents = np.bincount(np.concatenate([left[split], right[split]]), minlength=count)
    if np.any(parents[1:] != 1):
        k = _first(parents[1:] != 1) + 1
        raise _Broken(
            f"{where}.children_left/right",
            f"node {k} is the child of {parents[k]} nodes, expected 1",
        )
    feature = tree.feature
    outside = split & ((feature < 0) | (feature >= tree.n_features))
    if outside.any():
        k = _first(outside)
        raise _Broken(
            f"{where}.feature[{k}]",
            f"{feature[k]}, expected a feature index in [0, {tree.n_features}) at a split",
        )
    threshold = tree.threshold
    if not np.all(np.isfinite(threshold[split])):
        k = _first(split & ~np.isfinite(threshold))
        raise _Broken(f"{where}.threshold[{k}]", f"{threshold[k]}, expected a finite number")
    value = _array(
        f"{where}.value",
        tree.value,
        ndim=3,
        kind="f",
        shape=(count, tree.n_outputs, tree.max_n_classes),
    )
    if n_classes is not None and n_classes != [1] and np.any(value < 0):
        k = tuple(int(i) for i in np.argwhere(value < 0)[0])
        raise _Broken(
            f"{where}.value", f"expected class weights >= 0, found {value[k]} at {list(k)}"
        )


def _check_bagging(where: str, model: Any, n_features: int | None) -> None:
    n = _n_in(where, model, n_features)
    classes = _classes(where, model)
    n_classes = _n_classes(where, model, classes)
    estimators = getattr(model, "estimators_", None)
    columns = getattr(model, "estimators_features_", None)
    if not isinstance(estimators, list) or not estimators:
        raise _Broken(f"{where}.estimators_", "expected a list of fitted estimators")
    if not isinstance(columns, list) or len(columns) != len(estimators):
        raise _Broken(
            f"{where}.estimators_features_",
            f"expected a list of {len(estimators)} feature index arrays, one per estimator",
        )
    if model.n_estimators != len(estimators):
        raise _Broken(
            f"{where}.n_estimators",
            f"{model.n_estimators}, expected the {len(estimators)} estimators it holds",
        )
    for k, (estimator, seen) in enumerate(zip(estimators, columns, strict=True)):
        seen = _array(f"{where}.estimators_features_[{k}]", seen, ndim=1, kind="iu")
        if seen.size < 1 or seen.min() < 0 or seen.max() >= n:
            raise _Broken(
                f"{where}.estimators_features_[{k}]",
                f"expected feature indices in [0, {n}), found {shorten(str(seen.tolist()))}",
            )
        _check_estimator(f"{where}.estimators_[{k}]", estimator, seen.size)
        labels = getattr(estimator, "classes_", None)
        if isinstance(labels, np.ndarray) and not np.all(np.isin(labels, np.arange(n_classes))):
            raise _Broken(
                f"{where}.estimators_[{k}].classes_",
                f"expected class indices in "
                f"[0, {n_classes}), found {shorten(str(labels.tolist()))}",
            )


def _check_calibrated(where: str, model: Any, n_features: int | None) -> None:
    """A CalibratedClassifierCV (Reform's ``calibration``): per fold, a classifier checked as
    any, and one calibrator of finite parameters for the positive class."""
    _n_in(where, model, n_features)
    classes = _classes(where, model)
    folds = getattr(model, "calibrated_classifiers_", None)
    if not isinstance(folds, list) or not folds:
        raise _Broken(f"{where}.calibrated_classifiers_", "expected a list of calibrated folds")
    for k, fold in enumerate(folds):
        at = f"{where}.calibrated_classifiers_[{k}]"
        if type(fold) is not _CalibratedClassifier:
            raise _Broken(at, f"expected a _CalibratedClassifier, found a {type(fold).__name__}")
        _check_estimator(f"{at}.estimator", fold.estimator, n_features)
        calibrators = fold.calibrators
        rows = 1 if classes.size == 2 else classes.size
        if not isinstance(calibrators, list) or len(calibrators) != rows:
            raise _Broken(f"{at}.calibrators", f"expected a list of {rows} calibrator(s)")
        for c, calibrator in enumerate(calibrators):
            here = f"{at}.calibrators[{c}]"
            if type(calibrator) is _SigmoidCalibration:
                for name in ("a_", "b_"):
                    value = getattr(calibrator, name, None)
                    if not isinstance(value, (float, np.floating)) or not math.isfinite(value):
                        raise _Broken(
                            f"{here}.{name}", f"expected a finite number, found {value!r}"
                        )
            elif type(calibrator) is IsotonicRegression:
                x = _array(f"{here}.X_thresholds_", calibrator.X_thresholds_, ndim=1, kind="f")
                _array(
                    f"{here}.y_thresholds_",
                    calibrator.y_thresholds_,
                    ndim=1,
                    kind="f",
                    shape=(x.size,),
                )
            else:
                raise _Broken(
                    here,
                    f"expected a sigmoid or isotonic calibrator, found {type(calibrator).__name__}",
                )


def _check_forest(where: str, model: Any, n_features: int | None) -> None:
    n = _n_in(where, model, n_features)
    classes = _classes(where, model)
    estimators = getattr(model, "estimators_", None)
    if not isinstance(estimators, list) or not estimators:
        raise _Broken(f"{where}.estimators_", "expected a list of fitted trees")
    for k, estimator in enumerate(estimators):
        _check_estimator(f"{where}.estimators_[{k}]", estimator, n)
        if getattr(estimator, "n_classes_", None) != classes.size:
            raise _Broken(
                f"{where}.estimators_[{k}].n_classes_",
                f"expected {classes.size}, "
                f"found {shorten(repr(getattr(estimator, 'n_classes_', None)))}",
            )


_INSIDE_DEPTH = 6  # containers followed inside an estimator of another kind


def _check_inside(
    where: str, value: Any, n_features: int | None, *, depth: int, seen: set[int]
) -> None:
    """The trees and neighbour trees anywhere inside an estimator this module does not know,
    each checked on its own terms (its own feature count)."""

    if id(value) in seen or depth > _INSIDE_DEPTH:
        return
    seen.add(id(value))
    if isinstance(value, Tree):
        _check_tree(where, value, n_features=None, n_outputs=None, n_classes=None)
    elif isinstance(value, (KDTree, BallTree)):
        _check_binary_tree(where, value, None)
    elif isinstance(value, BaseEstimator) and depth > 0:
        _check_estimator(where, value, None)
    elif isinstance(value, dict):
        for key, item in value.items():
            _check_inside(_child(where, str(key)), item, n_features, depth=depth + 1, seen=seen)
    elif isinstance(value, (list, tuple)) or (
        isinstance(value, np.ndarray) and value.dtype.hasobject
    ):
        for k, item in enumerate(value.ravel() if isinstance(value, np.ndarray) else value):
            _check_inside(f"{where}[{k}]", item, n_features, depth=depth + 1, seen=seen)
