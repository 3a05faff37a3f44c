"""Detectors the CLI can build from its arguments: a small registry, one entry per detector.

Adding a detector is one decorated function (and, when it takes options, one function adding
them to the parser)::

    def _gcff_arguments(parser):
        parser.add_argument("--stride", type=float, default=0.7, help="metres")

    @register_detector("gcff", help="GCFF graph-cut baseline", add_arguments=_gcff_arguments)
    def _gcff(args):
        from reform import GCFF
        return GCFF(stride=args.stride)

A builder returns a detector ready to ``predict(frames)`` (one full partition per frame); the
CLI never fits it. Options of every registered detector are added to ``evaluate`` and
``detect``; a builder reads the ones it needs and ignores the rest.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from sim.cli._common import CliError

__all__ = [
    "DETECTORS",
    "DetectorSpec",
    "add_detector_arguments",
    "build_detector",
    "detector_params",
    "register_detector",
]


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


DETECTORS: dict[str, DetectorSpec] = {}


def register_detector(
    name: str,
    *,
    help: str,  # noqa: A002 - argparse's word
    add_arguments: Callable[[argparse.ArgumentParser], None] | None = None,
) -> Callable[[Callable[[argparse.Namespace], Any]], Callable[[argparse.Namespace], Any]]:
    """Decorator registering ``build(args) -> detector`` under ``name``."""

    def decorate(build: Callable[[argparse.Namespace], Any]) -> Callable[[argparse.Namespace], Any]:
        if name in DETECTORS:
            raise ValueError(f"detector {name!r} is already registered")
        DETECTORS[name] = DetectorSpec(
            name=name, help=help, build=build, add_arguments=add_arguments
        )
        return build

    return decorate


@register_detector("majority", help="majority baseline: everyone alone, every pair 'not together'")
def _majority(args: argparse.Namespace) -> Any:  # noqa: ARG001
    from reform import Majority

    return Majority()


def add_detector_arguments(parser: argparse.ArgumentParser) -> None:
    """``--detector NAME`` plus the options of every registered detector."""
    choices = "; ".join(f"{spec.name}: {spec.help}" for spec in DETECTORS.values())
    parser.add_argument(
        "--detector", required=True, choices=tuple(DETECTORS), metavar="NAME", help=choices
    )
    for spec in DETECTORS.values():
        if spec.add_arguments is not None:
            spec.add_arguments(parser)


def build_detector(args: argparse.Namespace) -> Any:
    """The detector named by ``args.detector``, built from the parsed options."""
    spec = DETECTORS.get(args.detector)
    if spec is None:
        raise CliError(f"--detector must be one of {sorted(DETECTORS)}, got {args.detector!r}")
    return spec.build(args)


def detector_params(detector: Any) -> dict[str, Any]:
    """The detector's ``get_params(deep=False)`` as JSON-ready values (others as ``str``)."""
    get_params = getattr(detector, "get_params", None)
    if get_params is None:
        return {}
    return {key: _json_value(value) for key, value in sorted(get_params(deep=False).items())}


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
