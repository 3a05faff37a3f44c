"""Detectors the CLI can build: every name of the catalogue (`reform.catalogue`), its options
from the catalogue's declaration, and plugins.

``--detector`` takes any name of the detector registry (the catalogue's built-ins, an installed
package's entry point) or a plugin's ``package.module:factory`` path. Its options come as
``--option NAME=VALUE`` (repeatable), checked against the catalogue's declaration of that
detector (type, range, unit: `reform.detectors.Option`), or from a settings file (``--settings
FILE.json``, `reform.settings`: what ``reform-sim tune`` writes). A few detectors keep flags of
their own, each flag belonging to the detectors that take it (GCFF's ``--stride``/``--mdl``/
``--settings FILE.mat``/``--gcff-orientation``, ``--tune-on`` for detectors that learn their
settings, REFORM's ``--model``); a flag given to another detector is an error naming both.

A detector that needs the dataset it runs on (``gcff-own``: the settings the dataset ships) is
specialised to it, and one that learns from training frames (``gcff-tuned``) is fitted on
``--tune-on`` (`reform.detectors.prepare_detector`); the CLI never fits a detector on the frames
it scores.

Building the parser imports the catalogue only (pure Python: ``--help`` stays light).
"""

from __future__ import annotations

import argparse
import inspect
import math
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from sim.cli._common import CliError, load_data
from sim.cli._numbers import ascii_float

__all__ = [
    "DETECTORS",
    "DetectorSpec",
    "add_detector_arguments",
    "add_detector_timeout",
    "build_detector",
    "check_detector",
    "cli_detector",
    "detector_name",
    "detector_params",
    "detector_timeout",
    "make_plugin",
]

# Where installed packages declare detectors (`reform.detectors.ENTRY_POINT_GROUP`; a test
# checks the two agree, the CLI's help must not import reform).
_ENTRY_POINT_GROUP = "reform_sim.detectors"


@dataclass(frozen=True)
class DetectorSpec:
    """One buildable detector.

    Attributes:
        name: the value of ``--detector``.
        help: one line for ``--help``.
        build: ``args -> detector`` ready to predict.
        add_arguments: adds the detector's own options to a parser, or None.
    """

    name: str
    help: str
    build: Callable[[argparse.Namespace], Any]
    add_arguments: Callable[[argparse.ArgumentParser], None] | None = None


# The catalogue's detectors the CLI builds from flags of their own (names of the registry); every
# other name is built from --option and --settings FILE.json by `_build_from_catalogue`.
DETECTORS: dict[str, DetectorSpec] = {}
# Flags that belong to some detectors only: dest -> (flag, the detectors that take it).
_OWN_FLAGS: dict[str, tuple[str, tuple[str, ...]]] = {
    "stride": ("--stride", ("gcff",)),
    "mdl": ("--mdl", ("gcff",)),
    "gcff_orientation": ("--gcff-orientation", ("gcff", "gcff-own", "gcff-tuned")),
    "model": ("--model", ("reform",)),
}


def cli_detector(
    name: str,
    *,
    help: str,  # noqa: A002 - argparse's word
    add_arguments: Callable[[argparse.ArgumentParser], None] | None = None,
) -> Callable[[Callable[[argparse.Namespace], Any]], Callable[[argparse.Namespace], Any]]:
    """Decorator registering ``build(args) -> detector`` for the registry's detector ``name``."""

    def decorate(build: Callable[[argparse.Namespace], Any]) -> Callable[[argparse.Namespace], Any]:
        if name in DETECTORS:
            raise ValueError(f"detector {name!r} already has a command-line builder")
        DETECTORS[name] = DetectorSpec(
            name=name, help=help, build=build, add_arguments=add_arguments
        )
        return build

    return decorate


def _gcff_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group(
        "gcff options",
        "Parameters carry units: metres and square metres (GCFF computes in centimetres; "
        "see reform.gcff). gcff runs with one stated setting, the REFORM paper's 0.7 m and "
        "3.0 m² unless --stride/--mdl/--settings say otherwise; gcff-own with the settings_gc.mat "
        "each sequence of the dataset ships; gcff-tuned with stride and mdl searched on --tune-on.",
    )
    group.add_argument(
        "--stride",
        type=ascii_float,
        metavar="S",
        help="gcff: distance of the o-space centre in front of each person, in METRES "
        "(default 0.7 m = 70 cm; the same as --option stride=S)",
    )
    group.add_argument(
        "--mdl",
        type=ascii_float,
        metavar="M",
        help="gcff: cost of opening one more group, in SQUARE METRES (default 3.0 m², the "
        "REFORM paper's 'MDL 30000' cm²; the reference code's 10000 cm² is 1.0 m²; the same as "
        "--option mdl=M)",
    )
    group.add_argument(
        "--gcff-orientation",
        choices=("body", "head"),
        default=None,
        help="gcff, gcff-own, gcff-tuned: orientation each person's o-space vote follows "
        "(default: body)",
    )


@cli_detector(
    "gcff",
    help="GCFF graph-cut baseline (Setti et al. 2015) with one stated setting",
    add_arguments=_gcff_arguments,
)
def _gcff(args: argparse.Namespace) -> Any:
    from reform import Gcff
    from reform.detectors import make_detector

    options = _options(args)
    flags = {
        key: value
        for key, value in (
            ("stride", args.stride),
            ("mdl", args.mdl),
            ("orientation", args.gcff_orientation),
        )
        if value is not None
    }
    both = sorted(set(flags) & set(options))
    if both:
        flag = "--gcff-orientation" if both[0] == "orientation" else f"--{both[0]}"
        raise CliError(f"gcff: give {both[0]} once ({flag} or --option {both[0]}=), not both")
    explicit = {**options, **flags}
    orientation = explicit.pop("orientation", None) or "body"
    settings = getattr(args, "settings", None)
    if settings is not None and not _is_json(settings):
        if explicit:
            raise CliError(
                f"gcff takes --settings FILE.mat or --stride/--mdl/--option; got both "
                f"(--settings and {', '.join(sorted(explicit))})"
            )
        per_pixel = getattr(args, "metres_per_pixel", None)
        if args.units == "px" and per_pixel is not None:  # settings in the dataset's pixels
            read = Gcff.from_settings_file(settings, units="m", orientation=orientation)
            return Gcff(
                stride=read.stride * per_pixel, mdl=read.mdl * per_pixel**2, orientation=orientation
            )
        return Gcff.from_settings_file(settings, units=args.units or "cm", orientation=orientation)
    from_file = _settings_options(args)
    _given_once("gcff", from_file, f"--settings {settings}", {**options, **flags})
    if "orientation" in flags or "orientation" in options or "orientation" not in from_file:
        explicit["orientation"] = orientation
    return make_detector("gcff", **{**from_file, **explicit})


@cli_detector(
    "gcff-own",
    help="GCFF with the settings_gc.mat each sequence of the dataset ships",
    add_arguments=None,
)
def _gcff_own(args: argparse.Namespace) -> Any:
    from reform.detectors import make_detector, prepare_detector

    options = {**_settings_options(args), **_options(args)}
    if args.gcff_orientation is not None:
        options["orientation"] = args.gcff_orientation
    own = make_detector("gcff-own", **options)
    detector = prepare_detector("gcff-own", own, dataset=load_data(args))
    shipped = "; ".join(
        f"{sequence}: stride {stride:g} m, mdl {mdl:g} m²"
        for sequence, (stride, mdl) in detector.settings.items()
    )
    print(f"gcff-own: the dataset's own settings_gc.mat ({shipped})", file=sys.stderr)
    return detector


@cli_detector(
    "gcff-tuned",
    help="GCFF with stride and mdl grid-searched on the annotated frames of --tune-on",
    add_arguments=None,
)
def _gcff_tuned(args: argparse.Namespace) -> Any:
    from reform.detectors import make_detector, prepare_detector

    options = {**_settings_options(args), **_options(args)}
    if args.gcff_orientation is not None:
        options["orientation"] = args.gcff_orientation
    train = _tuning_frames(args)
    tuned = prepare_detector("gcff-tuned", make_detector("gcff-tuned", **options), training=train)
    print(
        f"gcff-tuned: tuned on {len(train)} frames of {args.tune_on}: stride {tuned.stride_:g} m, "
        f"mdl {tuned.mdl_:g} m² (F1 at T={tuned.threshold} {tuned.grid_search_.best_f1:.3f})",
        file=sys.stderr,
    )
    return tuned


def _is_json(path: str) -> bool:
    return str(path).lower().endswith(".json")


def _reform_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--model",
        metavar="FILE.skops",
        help="reform: a model file written by `reform-sim train` (.skops)",
    )


@cli_detector(
    "reform",
    help="REFORM (Hedayati et al. 2020) from a model trained with `reform-sim train` (--model)",
    add_arguments=_reform_arguments,
)
def _reform(args: argparse.Namespace) -> Any:
    from reform.persistence import load_model

    given = {"model": args.model} if args.model is not None else {}
    options = _options(args)
    _given_once("reform", options, "--option", given)
    from_file = _settings_options(args)
    _given_once("reform", from_file, f"--settings {args.settings}", {**options, **given})
    model = {**from_file, **options, **given}.get("model")
    if model is None:
        raise CliError(
            "--detector reform needs --model MODEL, --option model=MODEL or a settings file "
            "naming its model (train one with `reform-sim train`)"
        )
    return load_model(model)


def _options(args: argparse.Namespace) -> dict[str, Any]:
    """``--option NAME=VALUE`` values, each read and checked by the catalogue's declaration of
    ``args.detector`` (a plugin's, undeclared: a JSON number, true/false, else the text)."""
    from reform.detectors import DetectorError, detector_info

    given = getattr(args, "option", None) or []
    info = detector_info(args.detector)
    out: dict[str, Any] = {}
    for text in given:
        key, equals, value = text.partition("=")
        key = key.strip()
        if not equals or not key.isidentifier():
            raise CliError(f"--option expects NAME=VALUE, got {text!r}")
        if key in out:
            raise CliError(f"--option {key} is given twice")
        if info.options:
            try:
                out[key] = info.option(key).parse(args.detector, value)
            except DetectorError as exc:
                raise CliError(str(exc)) from None
        else:
            out[key] = _literal(value)
    return out


def _literal(text: str) -> Any:
    """A plugin's undeclared option value: a JSON number or boolean, else the text itself."""
    import json

    try:
        value = json.loads(text)
    except ValueError:
        return text
    return value if isinstance(value, (int, float, bool)) else text


def _settings_options(args: argparse.Namespace) -> dict[str, Any]:
    """The options of a ``--settings FILE.json`` (`reform.settings`), checked to be
    ``args.detector``'s; ``{}`` without one."""
    from reform.detectors import DetectorError
    from reform.settings import read_settings

    path = getattr(args, "settings", None)
    if path is None or not _is_json(path):
        return {}
    try:
        settings = read_settings(path)
    except DetectorError as exc:
        raise CliError(str(exc)) from None
    if settings.detector != args.detector:
        raise CliError(
            f"--settings {path} holds settings of detector {settings.detector!r}, not of "
            f"--detector {args.detector}"
        )
    return dict(settings.options)


def _given_once(detector: str, first: dict[str, Any], source: str, then: dict[str, Any]) -> None:
    """CliError for an option both in ``first`` (given by ``source``: a settings file, or
    ``--option``) and in ``then`` (given besides): one would be used and the other dropped."""
    both = sorted(set(first) & set(then))
    if both:
        key = both[0]
        raise CliError(
            f"--detector {detector}: option {key} is given twice ({first[key]!r} by {source}, "
            f"{then[key]!r} besides); give it once"
        )


def _build_from_catalogue(args: argparse.Namespace) -> Any:
    """A catalogued (or installed, or plugin) detector from ``--settings FILE.json`` and
    ``--option``, given the dataset or the ``--tune-on`` frames it needs."""
    from reform.detectors import DetectorError, detector_info, prepare_detector

    name = args.detector
    from_file, given = _settings_options(args), _options(args)
    _given_once(name, from_file, f"--settings {getattr(args, 'settings', None)}", given)
    options = {**from_file, **given}
    detector = make_plugin(name, deadline_s=getattr(args, "detector_timeout", None), **options)
    needs = detector_info(name).needs if ":" not in name else ""
    training = None
    if needs == "training":
        training = _tuning_frames(args)
    try:
        return prepare_detector(
            name,
            detector,
            dataset=load_data(args) if needs == "dataset" else None,
            training=training,
        )
    except DetectorError as exc:
        raise CliError(str(exc)) from None


def _tuning_frames(args: argparse.Namespace) -> Any:
    """The annotated frames of ``--tune-on`` (never the frames scored); CliError without it."""
    from reform.datasets import load_dataset, resolve

    source = getattr(args, "tune_on", None)
    if source is None:
        raise CliError(
            f"--detector {args.detector} learns its settings from annotated training frames: "
            "give --tune-on PATH|NAME (a dataset other than the one scored)"
        )
    train = load_dataset(resolve(source)).annotated()
    if not train:
        raise CliError(f"--tune-on {source}: no annotated frames to tune on")
    print(
        f"{args.detector}: learning from {len(train)} annotated frames of {source} ...",
        file=sys.stderr,
    )
    return train


def detector_name(text: str) -> str:
    """``--detector``'s type: a registry name or a plugin's ``package.module:factory`` path.

    A path is only read here (imported when the detector is made); a name that is neither
    built in nor installed is an argparse error listing the known ones.
    """
    if ":" in text or text in DETECTORS:
        return text
    from reform.detectors import detector_names

    known = detector_names()
    if text not in known:
        raise argparse.ArgumentTypeError(
            f"invalid choice: {text!r} (choose from {', '.join(known)}, or give "
            "package.module:factory)"
        )
    return text


def detector_timeout(text: str) -> float:
    """``--detector-timeout``'s type: a duration above zero, as seconds
    (`reform.deadline.duration`); refused in one line before any work."""
    from reform.datasets.errors import shorten
    from reform.deadline import DURATION_FORM, duration

    seconds = duration(text)
    if seconds is None:
        raise argparse.ArgumentTypeError(f"expected {DURATION_FORM}, got {shorten(repr(text))}")
    return seconds


def add_detector_timeout(parser: argparse.ArgumentParser) -> None:
    """``--detector-timeout DURATION``: the deadline on a detector's code
    (`reform.detectors.make_detector`, `reform.detectors.run_detector`)."""
    parser.add_argument(
        "--detector-timeout",
        type=detector_timeout,
        metavar="DURATION",
        default=None,
        help="how long a detector may take to import its module, to be made by its factory, and "
        "to predict each frame (N frames in one call: N times it); seconds, or 90s, 2m, 500ms. "
        "At the deadline the run ends in one line naming the detector, what it was doing and the "
        "frame (default: 60 s to import and to make; 5 s a frame plus 0.05 s for each pair of "
        "people in it)",
    )


def catalogue_help() -> str:
    """Every catalogued detector with its help line and declared options, for ``--help``."""
    from reform.detectors import detector_info, detector_names

    lines = []
    for name in detector_names():
        try:
            info = detector_info(name)
        except Exception:  # noqa: BLE001 - a broken installed package must not break --help
            continue
        options = "; ".join(option.describe() for option in info.options)
        lines.append(f"{name}: {info.help}" + (f" [options: {options}]" if options else ""))
    return " | ".join(lines)


def add_detector_arguments(parser: argparse.ArgumentParser) -> None:
    """``--detector NAME``, ``--option``, ``--settings``, ``--tune-on`` and the flags of the
    detectors that keep their own."""
    parser.add_argument(
        "--detector",
        type=detector_name,
        metavar="NAME",
        help=f"the detector: {catalogue_help()}; or the name an installed package gives in the "
        f"entry-point group {_ENTRY_POINT_GROUP}; or package.module:factory, a detector of your "
        "own (the current folder is searched too). --model alone implies reform; --settings "
        "FILE.json alone implies the detector it names",
    )
    parser.add_argument(
        "--option",
        action="append",
        metavar="NAME=VALUE",
        help="an option of the detector (repeatable), as the catalogue declares it above "
        "(e.g. --detector gcff --option stride=0.6); values are checked against its range",
    )
    parser.add_argument(
        "--settings",
        metavar="FILE",
        help="the detector's settings from a file: FILE.json as `reform-sim tune` writes it (any "
        "detector), or, for gcff, a GCFF settings_gc.mat in centimetres and cm² (in metres "
        "when --units m is given)",
    )
    parser.add_argument(
        "--tune-on",
        metavar="PATH|NAME",
        help="annotated training frames for a detector that learns its settings (gcff-tuned "
        "grid-searches stride and mdl on them, objective F1 at T = 2/3); give training data "
        "only, never the dataset scored",
    )
    add_detector_timeout(parser)
    for spec in DETECTORS.values():
        if spec.add_arguments is not None:
            spec.add_arguments(parser)


def make_plugin(name: str, *, deadline_s: float | None = None, **options: Any) -> Any:
    """The registry's detector ``name`` made with ``options``, the current folder searched
    for a ``module:factory`` path after the installed packages, as ``python -m`` would; its
    import and its factory each within ``deadline_s`` seconds (`make_detector`'s default
    without it).

    Raises:
        reform.detectors.DetectorError: one line, if it cannot be found or made.
    """
    from reform.detectors import make_detector

    if ":" in name and os.getcwd() not in sys.path and "" not in sys.path:
        sys.path.append(os.getcwd())
    return make_detector(name, deadline_s=deadline_s, **options)


def check_detector(args: argparse.Namespace) -> DetectorSpec:
    """The detector the options name (``--model`` alone: reform; ``--settings FILE.json``
    alone: the detector it names), its options checked: called up front, before the data are
    read. A detector without flags of its own is made now from ``--option`` and ``--settings``
    (a plugin that does not import, an unknown option, a value out of range fail before any
    data are read).

    Raises:
        CliError: no detector named, a flag of another detector, a malformed option.
        reform.detectors.DetectorError: a detector that cannot be made.
    """
    if args.detector is None:
        settings = getattr(args, "settings", None)
        if getattr(args, "model", None) is not None:
            args.detector = "reform"
        elif settings is not None and _is_json(settings):
            from reform.detectors import DetectorError
            from reform.settings import read_settings

            try:
                args.detector = read_settings(settings).detector
            except DetectorError as exc:
                raise CliError(str(exc)) from None
        else:
            raise CliError(
                "give --detector NAME, or --model MODEL for a trained REFORM model, or "
                "--settings FILE.json"
            )
    for dest, (_flag, takers) in _OWN_FLAGS.items():
        if getattr(args, dest, None) is not None and args.detector not in takers:
            others = [
                f for d, (f, t) in _OWN_FLAGS.items() if t == takers and getattr(args, d, None)
            ]
            what = "is an option" if len(others) == 1 else "are options"
            raise CliError(
                f"{', '.join(others)} {what} of --detector {' or '.join(takers)}, not of "
                f"--detector {args.detector}"
            )
    settings = getattr(args, "settings", None)
    if settings is not None and not _is_json(settings) and args.detector != "gcff":
        raise CliError(
            f"--settings {settings}: a GCFF settings_gc.mat is read by --detector gcff only; "
            f"--detector {args.detector} takes a settings file FILE.json (`reform-sim tune`)"
        )
    if getattr(args, "tune_on", None) is not None and not _learns(args.detector):
        raise CliError(
            f"--tune-on is for a detector that learns its settings from training frames "
            f"(gcff-tuned), not for --detector {args.detector}"
        )
    spec = DETECTORS.get(args.detector)
    if spec is not None:
        _options(args)  # malformed or out-of-range options fail before any data are read
        _settings_options(args)  # a settings file of another detector is not left unread
        return spec
    _options(args)
    _settings_options(args)
    return DetectorSpec(name=args.detector, help="catalogue", build=_build_from_catalogue)


def _learns(name: str) -> bool:
    from reform.detectors import DetectorError, detector_info

    try:
        return ":" not in name and detector_info(name).needs == "training"
    except DetectorError:
        return False


def build_detector(args: argparse.Namespace) -> Any:
    """The detector named by ``args.detector``, built from the parsed options (checked by
    :func:`check_detector`)."""
    return check_detector(args).build(args)


def detector_params(detector: Any) -> dict[str, Any]:
    """The detector's ``get_params(deep=False)`` as JSON-ready values (others as ``str``)."""
    get_params = getattr(detector, "get_params", None)
    if get_params is None:
        return {}
    try:
        deep = "deep" in inspect.signature(get_params).parameters
    except (TypeError, ValueError):  # no signature to read: call it as scikit-learn does
        deep = True
    try:  # scikit-learn's get_params(deep=False), or a get_params of the detector's own
        items = sorted(dict(get_params(deep=False) if deep else get_params()).items())
    except Exception as exc:  # the detector is someone's code: report it in one line
        what = " ".join(f"{type(exc).__name__}: {exc}".split())
        raise CliError(
            f"the detector's get_params() raised {what} (expected a dict of its parameters)"
        ) from None
    return {str(key): _json_value(value) for key, value in items}


def _json_value(value: Any) -> Any:
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, (list, tuple)):
        return [_json_value(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _json_value(v) for k, v in value.items()}
    item = getattr(value, "item", None)  # numpy scalars
    if callable(item) and getattr(value, "ndim", None) == 0:
        return _json_value(item())
    return str(value)
