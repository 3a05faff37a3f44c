"""Pieces the subcommands share."""

from __future__ import annotations

import argparse
from typing import Any

FORMATS = ("salsa", "babble", "gcff", "parquet")


class CliError(Exception):
    """A user-facing error: printed as one line by ``reform-sim``, exit status 2."""


def add_data_arguments(parser: argparse.ArgumentParser, *, flag: str = "--data") -> None:
    """``--data PATH [--format F] [--units cm|m]``: where a dataset is and how to read it."""
    parser.add_argument(flag, required=True, metavar="PATH", help="dataset file or folder")
    parser.add_argument(
        "--format",
        choices=FORMATS,
        default=None,
        help="dataset format (default: detected from the path)",
    )
    parser.add_argument(
        "--units",
        choices=("cm", "m"),
        default=None,
        help="length unit of the file's positions (GCFF folders: default cm; others fixed)",
    )


def load_data(args: argparse.Namespace, *, attribute: str = "data"):
    """Loads the dataset named by :func:`add_data_arguments`."""
    from reform.datasets import load_dataset

    return load_dataset(getattr(args, attribute), format=args.format, units=args.units)


# Sensor flags: field of sim.Sensor -> (flag, unit shown in the help).
_SENSOR_NUMBERS = {
    "fov_deg": ("--fov-deg", "horizontal field of view, degrees"),
    "min_range": ("--min-range", "nearest distance seen, metres"),
    "max_range": ("--max-range", "farthest distance seen, metres"),
    "position_noise": ("--position-noise", "position noise per axis (std), metres"),
    "yaw_noise": ("--yaw-noise", "yaw noise (std), radians"),
    "dropout": ("--dropout", "probability that a seen person is missed"),
}
_SENSOR_SWITCHES = {
    "occlusion": ("--occlusion", "other bodies hide people (default: yes)"),
    "include_robot": ("--include-robot", "the observed frames hold the robot (default: yes)"),
}


def add_sensor_arguments(parser: argparse.ArgumentParser) -> None:
    """The robot sensor's flags (fields of `sim.Sensor`), used with ``--view robot``."""
    sensor = parser.add_argument_group("sensor (with --view robot)")
    for name, (flag, text) in _SENSOR_NUMBERS.items():
        sensor.add_argument(flag, dest=f"sensor_{name}", type=float, default=None, help=text)
    for name, (flag, text) in _SENSOR_SWITCHES.items():
        sensor.add_argument(
            flag,
            dest=f"sensor_{name}",
            action=argparse.BooleanOptionalAction,
            default=None,
            help=text,
        )


def parse_overrides(scenario: str, items: list[str]) -> dict[str, Any]:
    """``--set`` items (``["people=18", "robot=true"]``) as typed options of ``scenario``."""
    import scenarios

    pairs: dict[str, str] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise CliError(f"--set must be KEY=VALUE, got {item!r}")
        if key in pairs:
            raise CliError(f"--set {key} given twice")
        pairs[key] = text
    if not pairs:
        return {}
    return scenarios.parse_options(scenario, pairs)


def sensor_options(args: argparse.Namespace) -> dict[str, Any] | None:
    """The sensor flags given (``None`` for the ground-truth view, where they are an error)."""
    given = {
        name: getattr(args, f"sensor_{name}")
        for name in (*_SENSOR_NUMBERS, *_SENSOR_SWITCHES)
        if getattr(args, f"sensor_{name}") is not None
    }
    if args.view == "truth":
        if given:
            flags = [(_SENSOR_NUMBERS | _SENSOR_SWITCHES)[n][0] for n in given]
            raise CliError(f"sensor options need --view robot, got {', '.join(flags)}")
        return None
    return given
