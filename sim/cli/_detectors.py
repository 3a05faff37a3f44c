"""Detectors the CLI can build: the built-ins from their options, any other from the registry.

``--detector`` takes any name of the detector registry (`reform.detectors`: the built-ins, an
installed package's entry point) or a plugin's ``package.module:factory`` path. The built-in
detectors that take options on the command line have a builder here, one entry per detector
(and, when it takes options, one function adding them to the parser)::

    def _gcff_arguments(parser):
        parser.add_argument("--stride", type=float, help="metres")

    @cli_detector("gcff", help="GCFF graph-cut baseline", add_arguments=_gcff_arguments)
    def _gcff(args):
        from reform import Gcff
        return Gcff(stride=args.stride)

Every other detector is made by `reform.detectors.make_detector` with no options. A builder
returns a detector ready to ``predict(frames)`` (one full partition per frame); the CLI never
fits it. Options of every builder are added to ``evaluate`` and ``detect``; a builder reads its
own. A detector's options default to None (not given), so that one given to another detector is
an error naming both (``--model is an option of --detector reform, not of --detector
majority``).

Building the parser imports nothing of `reform` (``--help`` stays light): the registry is asked
when a ``--detector`` value is parsed.
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

__all__ = [
    "DETECTORS",
    "DetectorSpec",
    "add_detector_arguments",
    "build_detector",
    "check_detector",
    "cli_detector",
    "detector_name",
    "detector_params",
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


# The built-in detectors the CLI builds from its own options (names of the registry).
DETECTORS: dict[str, DetectorSpec] = {}


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


@cli_detector("majority", help="majority baseline: everyone alone, every pair 'not together'")
def _majority(args: argparse.Namespace) -> Any:  # noqa: ARG001
    from reform.detectors import make_detector

    return make_detector("majority")


def _gcff_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group(
        "gcff options",
        "Parameters carry units: metres and square metres (GCFF computes in centimetres; "
        "see reform.gcff). With none of --stride/--mdl, --settings, --tune-on, a GCFF folder's "
        "own settings_gc.mat is used when present, else the reference code's 70 cm / 10000 cm².",
    )
    group.add_argument(
        "--stride",
        type=float,
        metavar="S",
        help="GCFF: distance of the o-space centre in front of each person, in METRES "
        "(default 0.7 m = the reference code's 70 cm)",
    )
    group.add_argument(
        "--mdl",
        type=float,
        metavar="M",
        help="GCFF: cost of opening one more group, in SQUARE METRES (default 1.0 m² = the "
        "reference code's 10000 cm²; the REFORM paper's 'MDL 30000' is 30000 cm² = 3.0 m²)",
    )
    group.add_argument(
        "--settings",
        metavar="FILE.mat",
        help="GCFF: read stride and mdl from a GCFF settings file, in centimetres and cm² "
        "(in metres when --units m is given)",
    )
    group.add_argument(
        "--tune-on",
        metavar="PATH|NAME",
        help="GCFF: grid-search stride and mdl on the annotated frames of this dataset "
        "(format detected; give training data only), objective: F1 at T = 2/3",
    )
    group.add_argument(
        "--gcff-orientation",
        choices=("body", "head"),
        default=None,
        help="GCFF: orientation each person's o-space vote follows (default: body)",
    )


@cli_detector(
    "gcff",
    help="GCFF graph-cut baseline (Setti et al. 2015), faithful to the reference code",
    add_arguments=_gcff_arguments,
)
def _gcff(args: argparse.Namespace) -> Any:
    import sys

    from reform import Gcff
    from reform.datasets import detect_format, load_dataset, resolve

    orientation = args.gcff_orientation or "body"
    explicit = args.stride is not None or args.mdl is not None
    given = [
        name
        for name, present in (
            ("--stride/--mdl", explicit),
            ("--settings", args.settings is not None),
            ("--tune-on", args.tune_on is not None),
        )
        if present
    ]
    if len(given) > 1:
        raise CliError(f"gcff takes one of --stride/--mdl, --settings, --tune-on; got {given}")
    if args.settings is not None:
        per_pixel = getattr(args, "metres_per_pixel", None)
        if args.units == "px" and per_pixel is not None:  # settings in the dataset's pixels
            read = Gcff.from_settings_file(args.settings, units="m", orientation=orientation)
            return Gcff(
                stride=read.stride * per_pixel, mdl=read.mdl * per_pixel**2, orientation=orientation
            )
        return Gcff.from_settings_file(
            args.settings, units=args.units or "cm", orientation=orientation
        )
    if args.tune_on is not None:
        train = load_dataset(args.tune_on).annotated()
        if not train:
            raise CliError(f"--tune-on {args.tune_on}: no annotated frames to tune on")
        tuned = Gcff(tune=True, orientation=orientation).fit(train)
        search = tuned.grid_search_
        print(
            f"gcff: tuned on {len(train)} frames of {args.tune_on}: stride {tuned.stride_:g} m, "
            f"mdl {tuned.mdl_:g} m² (F1 at T=2/3 {search.best_f1:.3f})",
            file=sys.stderr,
        )
        return Gcff(stride=tuned.stride_, mdl=tuned.mdl_, orientation=orientation)
    if explicit:
        defaults = Gcff()
        stride = defaults.stride if args.stride is None else args.stride
        mdl = defaults.mdl if args.mdl is None else args.mdl
        return Gcff(stride=stride, mdl=mdl, orientation=orientation)
    if (args.format or detect_format(resolve(args.data))) == "gcff":
        from reform.gcff import GcffBySequence

        dataset = load_data(args)
        try:
            detector = GcffBySequence.from_dataset(dataset, orientation=orientation)
        except ValueError as exc:
            # A sequence ships no usable settings_gc.mat: the reference's defaults, said aloud.
            defaults = Gcff()
            print(
                f"gcff: {' '.join(str(exc).split())}; using the reference's defaults (stride "
                f"{defaults.stride:g} m, mdl {defaults.mdl:g} m²) for every sequence; give "
                "--stride/--mdl or --settings to choose",
                file=sys.stderr,
            )
            detector = None
        if detector is not None:
            shipped = "; ".join(
                f"{sequence}: stride {stride:g} m, mdl {mdl:g} m²"
                for sequence, (stride, mdl) in detector.settings.items()
            )
            print(f"gcff: the dataset's own settings_gc.mat ({shipped})", file=sys.stderr)
            if len(detector.settings) == 1:
                ((stride, mdl),) = detector.settings.values()
                return Gcff(stride=stride, mdl=mdl, orientation=orientation)
            return detector
    return Gcff(orientation=orientation)


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

    if args.model is None:
        raise CliError("--detector reform needs --model MODEL (train one with `reform-sim train`)")
    return load_model(args.model)


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


def add_detector_arguments(parser: argparse.ArgumentParser) -> None:
    """``--detector NAME`` plus the options of every built-in detector."""
    choices = "; ".join(f"{spec.name}: {spec.help}" for spec in DETECTORS.values())
    parser.add_argument(
        "--detector",
        type=detector_name,
        metavar="NAME",
        help=f"{choices}; or the name an installed package gives in the entry-point group "
        f"{_ENTRY_POINT_GROUP}; or package.module:factory, a detector of your own (the "
        "current folder is searched too) (--model alone implies reform)",
    )
    options: dict[str, tuple[tuple[str, str], ...]] = {}
    for spec in DETECTORS.values():
        if spec.add_arguments is not None:
            known = len(parser._actions)
            spec.add_arguments(parser)
            options[spec.name] = tuple(
                (action.option_strings[0], action.dest) for action in parser._actions[known:]
            )
    parser.set_defaults(detector_options=options)


def make_plugin(name: str) -> Any:
    """The registry's detector ``name`` (a plugin: no options), the current folder searched
    for a ``module:factory`` path after the installed packages, as ``python -m`` would.

    Raises:
        reform.detectors.DetectorError: one line, if it cannot be found or made.
    """
    from reform.detectors import make_detector

    if ":" in name and os.getcwd() not in sys.path and "" not in sys.path:
        sys.path.append(os.getcwd())
    return make_detector(name)


def check_detector(args: argparse.Namespace) -> DetectorSpec:
    """The detector the options name (``--model`` alone: reform), its options checked: called
    up front, before the data are read. A detector without a builder here is made now (a
    plugin that does not import or has no ``predict`` fails before any data are read).

    Raises:
        CliError: no detector named, or an option of another detector given.
        reform.detectors.DetectorError: a plugin that cannot be made.
    """
    if args.detector is None:
        if getattr(args, "model", None) is None:
            raise CliError("give --detector NAME, or --model MODEL for a trained REFORM model")
        args.detector = "reform"
    for name, flags in getattr(args, "detector_options", {}).items():
        if name == args.detector:
            continue
        given = [flag for flag, dest in flags if getattr(args, dest, None) is not None]
        if given:
            what = "is an option" if len(given) == 1 else "are options"
            raise CliError(
                f"{', '.join(given)} {what} of --detector {name}, not of --detector {args.detector}"
            )
    spec = DETECTORS.get(args.detector)
    if spec is not None:
        return spec
    detector = make_plugin(args.detector)
    return DetectorSpec(name=args.detector, help="plugin", build=lambda _args: detector)


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
