"""The detector registry (reform.detectors): names, plugins, entry points, every error message.
The contract every registered detector keeps is tests/reform/test_detector_contract.py."""

from __future__ import annotations

import json
import shutil
import sys
import textwrap
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from cli_errors import cli_error
from toy_scenes import toy_frames

import reform.detectors
from reform import (
    Dataset,
    DetectorError,
    Gcff,
    Majority,
    Reform,
    check_predictions,
    detector_info,
    detector_names,
    fit_detector,
    make_detector,
    register_detector,
    run_detector,
    save_model,
    write_parquet,
)
from reform.classifiers import make_classifier
from reform.detectors import ENTRY_POINT_GROUP, Detector
from sim.cli import main

BUILT_IN = ("gcff", "majority", "reform")


def as_sets(partition) -> set[frozenset[int]]:
    return {frozenset(int(m) for m in group) for group in partition}


@pytest.fixture
def registry(monkeypatch):
    """A registry of its own for the test: what it registers is gone afterwards."""
    monkeypatch.setattr(reform.detectors, "_REGISTRY", dict(reform.detectors._REGISTRY))


@pytest.fixture(scope="module")
def model_path(tmp_path_factory) -> Path:
    model = Reform(make_classifier("logistic-regression")).fit(toy_frames(0, 30))
    return save_model(model, tmp_path_factory.mktemp("model") / "model.skops")


@pytest.fixture
def plugins(tmp_path, monkeypatch) -> Iterator[Path]:
    """A folder on sys.path holding the module ``labplugin`` (good and broken detectors)."""
    (tmp_path / "labplugin.py").write_text(
        textwrap.dedent(
            """
            class Alone:
                def __init__(self, *, scale=1.0):
                    self.scale = scale
                    self.fitted_on = None

                def fit(self, frames):
                    self.fitted_on = len(frames)
                    return self

                def predict(self, frames):
                    return [[(int(i),) for i in f.ids] for f in frames]

            def make(*, scale=1.0):
                return Alone(scale=scale)

            def make_nothing():
                return None

            def make_broken():
                raise RuntimeError("no licence\\nfound")

            class RaisesLate(Alone):
                def predict(self, frames):
                    if any(f.time >= 3 for f in frames):
                        1 / 0
                    return super().predict(frames)

            class Forgets(Alone):
                def predict(self, frames):
                    return [[(int(f.ids[0]),)] for f in frames]

            detector = Alone()
            number = 3
            """
        )
    )
    (tmp_path / "badimport.py").write_text("import numpy\n1 / 0\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield tmp_path
    for module in ("labplugin", "badimport"):
        sys.modules.pop(module, None)


def dist_info(folder: Path, name: str, entry_points: dict[str, str]) -> None:
    """Installed-package metadata declaring ``entry_points`` in the detectors' group."""
    info = folder / f"{name}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    lines = "".join(f"{key} = {value}\n" for key, value in entry_points.items())
    (info / "entry_points.txt").write_text(f"[{ENTRY_POINT_GROUP}]\n{lines}")


# ------------------------------------------------------------------------------------------------
# The registry


def test_the_built_ins_are_registered():
    assert set(BUILT_IN) <= set(detector_names())
    assert detector_names() == tuple(sorted(detector_names()))
    assert {detector_info(name).source for name in BUILT_IN} == {"built-in"}
    assert isinstance(make_detector("majority"), Majority)


def test_gcff_options_are_in_metres():
    detector = make_detector("gcff", stride=0.6, mdl=2.0, orientation="head")
    assert isinstance(detector, Gcff)
    assert (detector.stride, detector.mdl, detector.orientation) == (0.6, 2.0, "head")


def test_reform_loads_a_model_file(model_path):
    detector = make_detector("reform", model=model_path)
    assert isinstance(detector, Reform)
    frames = toy_frames(1, 3)
    assert detector.predict(frames) == Reform(make_classifier("logistic-regression")).fit(
        toy_frames(0, 30)
    ).predict(frames)


def test_register_a_factory_and_a_decorated_one(registry):
    def make_alone():
        return Majority()

    assert register_detector("alone", make_alone, help="everyone alone") is make_alone

    @register_detector("alone-too", help="everyone alone, again")
    def make_alone_too(*, note: str = ""):
        return Majority()

    assert make_alone_too(note="x").predict(toy_frames(0, 1))
    assert {"alone", "alone-too"} <= set(detector_names())
    assert isinstance(make_detector("alone-too", note="hi"), Majority)
    info = detector_info("alone")
    assert (info.help, info.source, info.factory) == ("everyone alone", "registered", make_alone)


def test_register_a_factory_by_its_import_path(registry, plugins):
    register_detector("lab", "labplugin:make", help="the lab's detector")
    detector = make_detector("lab", scale=2.0)
    assert type(detector).__name__ == "Alone" and detector.scale == 2.0


def test_a_plugin_by_its_path(plugins):
    detector = make_detector("labplugin:make", scale=3.0)
    assert (type(detector).__name__, detector.scale) == ("Alone", 3.0)
    assert isinstance(detector, Detector)
    assert type(make_detector("labplugin:Alone")).__name__ == "Alone"  # a class is a factory
    instance = make_detector("labplugin:detector")  # a detector object is used as it is
    assert instance is __import__("labplugin").detector


def test_an_installed_packages_entry_point(tmp_path, monkeypatch, plugins):
    dist_info(tmp_path, "labplugin", {"lab-alone": "labplugin:make"})
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "lab-alone" in detector_names()
    info = detector_info("lab-alone")
    assert info.source == "entry point lab-alone = labplugin:make of labplugin 0.1"
    assert info.factory == "labplugin:make"
    assert make_detector("lab-alone", scale=5.0).scale == 5.0


def test_entry_points_are_read_on_lookup_and_loaded_when_made(tmp_path, monkeypatch):
    # The entry point's module does not exist: listing and looking up the name import nothing,
    # making the detector does.
    dist_info(tmp_path, "ghost", {"ghost": "ghost_module_that_is_not_there:make"})
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "ghost" in detector_names()
    assert detector_info("ghost").factory == "ghost_module_that_is_not_there:make"
    with pytest.raises(DetectorError, match="^detector 'ghost': cannot import module"):
        make_detector("ghost")


def test_a_package_installed_or_removed_in_a_folder_already_searched_is_seen(tmp_path, monkeypatch):
    # The lookups are kept between calls: a package's metadata appearing in, then leaving, a
    # folder that was already on the path (as `pip install` and `pip uninstall` do) is seen.
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "lab-late" not in detector_names()
    dist_info(tmp_path, "latelab", {"lab-late": "labplugin:make"})
    assert "lab-late" in detector_names()
    assert detector_info("lab-late").factory == "labplugin:make"
    shutil.rmtree(tmp_path / "latelab-0.1.dist-info")
    assert "lab-late" not in detector_names()
    with pytest.raises(DetectorError, match="^unknown detector 'lab-late'"):
        detector_info("lab-late")


# ------------------------------------------------------------------------------------------------
# Every error, one line each


@pytest.mark.parametrize(
    ("name", "options", "message"),
    [
        pytest.param(
            "oracle",
            {},
            r"^unknown detector 'oracle'; known detectors: (\S+, )*gcff, (\S+, )*majority, "
            r"(\S+, )*reform(, .*)? \(or give a plugin as package\.module:factory\)$",
            id="unknown-name",
        ),
        pytest.param(
            "no_such_lab_module:make",
            {},
            r"^detector 'no_such_lab_module:make': cannot import module 'no_such_lab_module': "
            r"ModuleNotFoundError: No module named 'no_such_lab_module' \(is the package "
            r"installed, or its folder on PYTHONPATH\?\)$",
            id="module-not-found",
        ),
        pytest.param(
            "badimport:make",
            {},
            r"^detector 'badimport:make': cannot import module 'badimport': "
            r"ZeroDivisionError: division by zero$",
            id="module-raises-on-import",
        ),
        pytest.param(
            "labplugin:nothing_here",
            {},
            r"^detector 'labplugin:nothing_here': module 'labplugin' has no attribute "
            r"'nothing_here'$",
            id="no-such-attribute",
        ),
        pytest.param(
            "labplugin:number",
            {},
            r"^detector 'labplugin:number': labplugin:number is a int \(3\), neither a factory "
            r"nor an object with a callable predict\(frames\)$",
            id="object-without-predict",
        ),
        pytest.param(
            "labplugin:make_nothing",
            {},
            r"^detector 'labplugin:make_nothing': its factory labplugin:make_nothing returned "
            r"None, which has no callable predict\(frames\)$",
            id="factory-returns-no-detector",
        ),
        pytest.param(
            "labplugin:make_broken",
            {},
            r"^detector 'labplugin:make_broken' could not be made: RuntimeError: no licence "
            r"found$",
            id="factory-raises",
        ),
        pytest.param(
            "labplugin:make",
            {"colour": "red"},
            r"^detector 'labplugin:make' has no option 'colour'; its options: scale$",
            id="unknown-option",
        ),
        pytest.param(
            "labplugin:detector",
            {"scale": 2},
            r"^detector 'labplugin:detector': labplugin:detector is a detector, not a factory, "
            r"so it takes no options \(got scale\)$",
            id="options-to-a-detector-object",
        ),
        pytest.param(
            "reform",
            {},
            r"^detector 'reform' needs the option model= \(its options: model, trusted\)$",
            id="missing-option",
        ),
        pytest.param(
            "gcff",
            {"stride_cm": 70},
            r"^detector 'gcff' has no option 'stride_cm'; its options: stride, mdl, orientation$",
            id="unknown-option-of-a-built-in",
        ),
        pytest.param(
            "reform",
            {"model": "/no/such/model.skops"},
            r"^detector 'reform' could not be made: FileNotFoundError: .*model\.skops",
            id="built-in-factory-raises",
        ),
        pytest.param(
            "labplugin:",
            {},
            r"^a detector path must read package\.module:factory, got 'labplugin:'$",
            id="malformed-path",
        ),
        pytest.param(
            "lab plugin:make",
            {},
            r"^a detector path must read package\.module:factory, got 'lab plugin:make'$",
            id="path-with-a-space",
        ),
    ],
)
def test_make_detector_errors(name, options, message, plugins):
    with pytest.raises(DetectorError, match=message) as caught:
        make_detector(name, **options)
    assert "\n" not in str(caught.value)


def test_a_name_registered_twice(registry):
    with pytest.raises(
        DetectorError, match=r"^detector 'gcff' is registered twice \(it is already built-in\)$"
    ):
        register_detector("gcff", Gcff, help="another GCFF")
    register_detector("mine", Majority, help="mine")
    with pytest.raises(DetectorError, match=r"^detector 'mine' is registered twice"):
        register_detector("mine", Majority, help="mine again")


def test_an_entry_point_named_as_a_built_in_is_registered_twice(tmp_path, monkeypatch):
    dist_info(tmp_path, "rival", {"gcff": "rival:make"})
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(
        DetectorError,
        match=r"^detector 'gcff' is registered twice: built-in; entry point gcff = rival:make "
        r"of rival 0\.1 \(uninstall one of the packages\)$",
    ):
        make_detector("gcff")
    assert detector_names().count("gcff") == 1


def test_a_package_registering_its_own_entry_point_is_one_source(tmp_path, monkeypatch, registry):
    """The extending guide's module registers itself, and its package declares the same
    detector as an entry point: making it twice works (importing it registers it)."""
    (tmp_path / "selfreg.py").write_text(
        "import reform\n"
        "from reform.majority import Majority\n\n"
        "class Close(Majority):\n"
        '    """Everyone alone, as the lab likes it."""\n\n'
        'reform.register_detector("close", Close)\n'
    )
    dist_info(tmp_path, "selfreg", {"close": "selfreg:Close"})
    monkeypatch.syspath_prepend(str(tmp_path))
    first, second = make_detector("close"), make_detector("close")
    assert type(first).__name__ == type(second).__name__ == "Close"
    assert detector_info("close").help == "Everyone alone, as the lab likes it."  # its docstring
    # another package's entry point of that name is still a second source
    (tmp_path / "other").mkdir()
    dist_info(tmp_path / "other", "rival", {"close": "rival:make"})
    monkeypatch.syspath_prepend(str(tmp_path / "other"))
    with pytest.raises(DetectorError, match=r"^detector 'close' is registered twice"):
        make_detector("close")


def test_help_defaults_to_the_factorys_docstring_or_path(registry):
    def make_alone():
        """Everyone alone.

        More lines."""
        return Majority()

    register_detector("alone", make_alone)
    register_detector("bare", lambda: Majority())
    register_detector("by-path", "labplugin:make")
    assert detector_info("alone").help == "Everyone alone."
    assert detector_info("bare").help.startswith("plugin test_detectors:")
    assert detector_info("by-path").help == "plugin labplugin:make"


@pytest.mark.parametrize(
    ("name", "factory", "help", "message"),
    [
        ("a:b", Majority, "x", r"^a detector name must be a non-empty word without ':'"),
        ("", Majority, "x", r"^a detector name must be a non-empty word"),
        ("two words", Majority, "x", r"^a detector name must be a non-empty word"),
        ("ok", Majority, "", r"^detector 'ok': help must be one line of text, got ''$"),
        ("ok", Majority, "one\ntwo", r"^detector 'ok': help must be one line of text"),
        (
            "ok",
            3,
            "x",
            r"^detector 'ok': the factory must be callable or a package\.module:factory path, "
            r"got a int \(3\)$",
        ),
        ("ok", "not a path", "x", r"^a detector path must read package\.module:factory"),
    ],
    ids=["colon", "empty", "space", "no-help", "two-lines", "not-callable", "bad-path"],
)
def test_register_detector_refuses(name, factory, help, message, registry):  # noqa: A002
    with pytest.raises(DetectorError, match=message):
        register_detector(name, factory, help=help)
    assert name not in reform.detectors._REGISTRY


def test_detector_info_wants_a_string():
    with pytest.raises(DetectorError, match=r"^a detector is named by a string .*got a int \(3\)"):
        detector_info(3)


# ------------------------------------------------------------------------------------------------
# Checked runs


FRAMES = toy_frames(3, 3, sizes=(2, 3), loners=1)  # ids 1-6, sequence "toy", times 0, 1, 2 s


class Returns:
    """A detector returning ``output`` whatever the frames."""

    def __init__(self, output):
        self.output = output

    def predict(self, frames):
        return self.output


def alone(frame):
    return [(int(i),) for i in frame.ids]


@pytest.mark.parametrize(
    ("output", "message"),
    [
        pytest.param(
            None,
            r"^lab: detector returned None, expected one partition per frame \(3 frames\)$",
            id="none",
        ),
        pytest.param(
            [alone(f) for f in FRAMES[:2]],
            r"^lab: detector returned 2 partitions for 3 frames$",
            id="too-few",
        ),
        pytest.param(
            [alone(FRAMES[0]), [*alone(FRAMES[1]), (99,)], alone(FRAMES[2])],
            r"^lab: detector output for frame 1 \(toy t=1 s\): person 99 \(group 6\) is not in "
            r"the frame \(ids \[1, 2, 3, 4, 5, 6\]\)$",
            id="unknown-person",
        ),
        pytest.param(
            [alone(FRAMES[0]), alone(FRAMES[1]), [(1, 2), (2, 3), (4,), (5,), (6,)]],
            r"^lab: detector output for frame 2 \(toy t=2 s\): person 2 appears twice "
            r"\(again in group 1\)$",
            id="someone-twice",
        ),
        pytest.param(
            [[(1, 2), (3,)], alone(FRAMES[1]), alone(FRAMES[2])],
            r"^lab: detector output for frame 0 \(toy t=0 s\): person 4 is in no group; a "
            r"prediction must be a full partition of the frame's ids, singletons included$",
            id="someone-missing",
        ),
        pytest.param(
            [alone(FRAMES[0]), [(1.5,), *alone(FRAMES[1])], alone(FRAMES[2])],
            r"^lab: detector output for frame 1 \(toy t=1 s\): group 0 holds 1\.5, expected an "
            r"integer person id$",
            id="non-integer-id",
        ),
        pytest.param(
            [[(), *alone(FRAMES[0])], alone(FRAMES[1]), alone(FRAMES[2])],
            r"^lab: detector output for frame 0 \(toy t=0 s\): group 0 is empty$",
            id="empty-group",
        ),
        pytest.param(
            [np.arange(1, 7) for _ in FRAMES],
            r"^lab: detector output for frame 0 \(toy t=0 s\): group 0 must be a sequence of "
            r"person ids, found ",
            id="labels-not-groups",
        ),
    ],
)
def test_check_predictions_names_the_detector_and_the_frame(output, message):
    with pytest.raises(DetectorError, match=message):
        check_predictions("lab", FRAMES, output)
    with pytest.raises(DetectorError, match=message):
        run_detector("lab", Returns(output), FRAMES)


def test_check_predictions_returns_the_partitions_as_a_list():
    output = (tuple(alone(f)) for f in FRAMES)  # a generator is a sequence of partitions too
    assert check_predictions("lab", FRAMES, output) == [tuple(alone(f)) for f in FRAMES]
    assert run_detector("majority", Majority(), FRAMES) == Majority().predict(FRAMES)


class RaisesAt:
    """Raises on the frame at time ``when`` (or only on batches of two or more frames)."""

    def __init__(self, when=None):
        self.when = when

    def predict(self, frames):
        if self.when is None and len(frames) > 1:
            raise MemoryError
        for frame in frames:
            if frame.time == self.when:
                raise LookupError("heading\nmissing")
        return [alone(f) for f in frames]


def test_run_detector_names_the_frame_that_raises():
    with pytest.raises(
        DetectorError,
        match=r"^lab: detector raised LookupError on frame 2 \(toy t=2 s\): heading missing$",
    ) as caught:
        run_detector("lab", RaisesAt(2.0), FRAMES)
    assert isinstance(caught.value.__cause__, LookupError)


def test_run_detector_on_a_batch_that_raises_only_together():
    with pytest.raises(
        DetectorError,
        match=r"^lab: detector raised MemoryError on a batch of 3 frames \(no frame alone\)$",
    ):
        run_detector("lab", RaisesAt(None), FRAMES)


class Yields:
    """Partitions one frame at a time (a generator), raising on the frame at time ``when``."""

    def __init__(self, when=None, lazy_groups=False):
        self.when, self.lazy_groups = when, lazy_groups

    def predict(self, frames):
        for frame in frames:
            if frame.time == self.when:
                raise RuntimeError("cannot read frame")
            yield iter(alone(frame)) if self.lazy_groups else alone(frame)


def test_lazy_output_is_read_inside_the_detector():
    """A generator's exception is the detector's, on the frame that raises it."""
    assert run_detector("lab", Yields(), FRAMES) == [alone(f) for f in FRAMES]
    assert run_detector("lab", Yields(lazy_groups=True), FRAMES) == [alone(f) for f in FRAMES]
    with pytest.raises(
        DetectorError,
        match=r"^lab: detector raised RuntimeError on frame 1 \(toy t=1 s\): cannot read frame$",
    ):
        run_detector("lab", Yields(when=1.0), FRAMES)


def test_a_detector_that_exits_is_one_line():
    class Exits(Returns):
        def predict(self, frames):
            sys.exit(3)

    with pytest.raises(DetectorError, match=r"^lab: detector raised SystemExit on frame 0 .*: 3$"):
        run_detector("lab", Exits(None), FRAMES)


def test_a_detector_never_sees_the_ground_truth():
    """An oracle that returns each frame's ground truth scores nothing: it is not given one."""

    class Oracle:
        seen = []

        def predict(self, frames):
            self.seen += [f.groups for f in frames]
            return [alone(f) for f in frames]

    assert all(f.groups is not None for f in FRAMES)
    oracle = Oracle()
    run_detector("lab", oracle, FRAMES)
    assert oracle.seen == [None] * len(FRAMES)
    assert all(f.groups is not None for f in FRAMES)  # the caller's frames keep theirs


def test_run_detector_wants_a_callable_predict():
    with pytest.raises(DetectorError, match=r"^lab: a str \('x'\) has no callable predict"):
        run_detector("lab", "x", FRAMES)


def test_fit_detector_fits_a_copy(plugins):
    detector = make_detector("labplugin:make")
    fitted = fit_detector("lab", detector, FRAMES)
    assert (fitted.fitted_on, detector.fitted_on) == (3, None)
    assert fit_detector("lab", Returns([]), FRAMES).output == []  # no fit: itself

    class FitRaises(Returns):
        def fit(self, frames):
            raise ValueError("needs head poses")

    with pytest.raises(
        DetectorError,
        match=r"^lab: detector's fit raised ValueError: needs head poses \(on 3 frames\)$",
    ):
        fit_detector("lab", FitRaises(None), FRAMES)

    class Locked(Returns):
        def fit(self, frames):
            return self

    locked = Locked(None)
    locked.lock = threading.Lock()
    with pytest.raises(
        DetectorError,
        match=r"^lab: the detector cannot be copied to be fitted \(copy.deepcopy raised "
        r"TypeError: cannot pickle '_thread.lock' object\)",
    ):
        fit_detector("lab", locked, FRAMES)


def test_the_command_lines_built_ins_are_registered_names():
    from sim.cli import _detectors

    assert set(_detectors.DETECTORS) <= set(detector_names())
    assert _detectors._ENTRY_POINT_GROUP == ENTRY_POINT_GROUP


# ------------------------------------------------------------------------------------------------
# The command line: any registered name or plugin path


@pytest.fixture
def toy_dataset(tmp_path) -> Path:
    path = tmp_path / "toy.parquet"
    frames = toy_frames(0, 6, sizes=(2, 3), loners=1)
    write_parquet(Dataset(frames=tuple(frames), name="toy", source="toy_scenes"), path)
    return path


def test_evaluate_and_detect_run_a_plugin(plugins, toy_dataset, tmp_path, capsys):
    out = tmp_path / "r.json"
    argv = ["evaluate", "--detector", "labplugin:make", "--data", toy_dataset, "--json", out]
    assert main([str(a) for a in argv]) == 0, capsys.readouterr().err
    result = json.loads(out.read_text())
    assert (result["detector"], result["frames"]) == ("labplugin:make", 6)
    groups = tmp_path / "groups.json"
    argv = ["detect", "--detector", "labplugin:make", "--data", toy_dataset, "--out", groups]
    assert main([str(a) for a in argv]) == 0, capsys.readouterr().err
    assert [r["groups"] for r in json.loads(groups.read_text())["frames"]] == [[]] * 6


@pytest.mark.parametrize("command", ["evaluate", "detect"])
@pytest.mark.parametrize(
    ("plugin", "message"),
    [
        (
            "labplugin:nothing_here",
            "detector 'labplugin:nothing_here': module 'labplugin' has no attribute 'nothing_here'",
        ),
        (
            "labplugin:make_nothing",
            "detector 'labplugin:make_nothing': its factory labplugin:make_nothing returned "
            "None, which has no callable predict(frames)",
        ),
        (
            "no_such_lab_module:make",
            "detector 'no_such_lab_module:make': cannot import module 'no_such_lab_module': "
            "ModuleNotFoundError: No module named 'no_such_lab_module' (is the package "
            "installed, or its folder on PYTHONPATH?)",
        ),
        (
            "labplugin:RaisesLate",
            "labplugin:RaisesLate: detector raised ZeroDivisionError on frame 3 (toy t=3 s): "
            "division by zero",
        ),
        (
            "labplugin:Forgets",
            "labplugin:Forgets: detector output for frame 0 (toy t=0 s): person 2 is in no "
            "group; a prediction must be a full partition of the frame's ids, singletons "
            "included",
        ),
    ],
    ids=["no-attribute", "no-predict", "no-module", "raises", "not-a-partition"],
)
def test_a_broken_plugin_is_one_line(
    command, plugin, message, plugins, toy_dataset, tmp_path, capsys
):
    argv = [command, "--detector", plugin, "--data", toy_dataset]
    if command == "detect":
        argv += ["--out", tmp_path / "groups.json"]
    assert cli_error(argv, capsys) == f"reform-sim {command}: error: {message}"
    assert not (tmp_path / "groups.json").exists()


def test_an_unknown_name_is_an_argparse_error_listing_the_names(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", "--detector", "oracle", "--data", "x"])
    assert exc.value.code == 2
    every = ", ".join(detector_names())
    assert (
        f"argument --detector: invalid choice: 'oracle' (choose from {every}, or give"
        in capsys.readouterr().err
    )
