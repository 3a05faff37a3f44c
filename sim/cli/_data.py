"""Placeholder: filled in by the subcommand's implementation."""

from __future__ import annotations


def register(subparsers) -> None:  # noqa: ARG001
    return None
