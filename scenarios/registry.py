"""Scenarios by name: ``register`` a factory, ``make`` a scenario, list ``names`` and ``options``.

A factory is a function ``factory(*, seed: int, option: type = default, ...) -> Scenario``.
Its keyword options (with type annotations ``int``, ``float``, ``bool``, ``str`` or a
``Literal`` of strings, and defaults) are the scenario's options; their help comes from the
factory's docstring (``Args:`` section). `make` checks the name and the options' names and types
before calling the factory, which checks their values (ranges, feasibility) before drawing
anything.
"""

from __future__ import annotations

import inspect
import math
import re
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal

from scenarios.scenario import Scenario

__all__ = [
    "Option",
    "ScenarioInfo",
    "describe",
    "make",
    "names",
    "options",
    "parse_options",
    "register",
]

_TYPES = (bool, int, float, str)
_TRUE = ("true", "yes", "on", "1")
_FALSE = ("false", "no", "off", "0")


@dataclass(frozen=True)
class Option:
    """One option of a scenario.

    Attributes:
        name: keyword name.
        type: ``bool``, ``int``, ``float`` or ``str``.
        default: the default value.
        help: one line (with the unit).
        choices: the allowed values of a ``str`` option with a fixed set, else ``None``.
    """

    name: str
    type: type
    default: Any
    help: str = ""
    choices: tuple[str, ...] | None = None

    @property
    def type_name(self) -> str:
        if self.choices is not None:
            return "{" + ",".join(self.choices) + "}"
        return self.type.__name__

    def check(self, value: Any, *, scenario: str) -> Any:
        """``value`` as this option's type; `ValueError` naming the option when it is not."""
        kind = self.type
        ok = False
        if kind is bool:
            ok = isinstance(value, bool)
        elif kind is int:
            ok = isinstance(value, int) and not isinstance(value, bool)
        elif kind is float:
            ok = isinstance(value, (int, float)) and not isinstance(value, bool)
            if ok:
                value = float(value)
                ok = math.isfinite(value)
        elif kind is str:
            ok = isinstance(value, str) and (self.choices is None or value in self.choices)
        if not ok:
            raise ValueError(
                f"{scenario}: option {self.name} must be {self._expected()}, got {value!r}"
            )
        return value

    def parse(self, text: str, *, scenario: str) -> Any:
        """The value of ``text`` (a command-line string) as this option's type."""
        kind = self.type
        try:
            if kind is bool:
                low = text.strip().lower()
                if low not in _TRUE + _FALSE:
                    raise ValueError
                value: Any = low in _TRUE
            elif kind is int:
                value = int(text)
            elif kind is float:
                value = float(text)
            else:
                value = text
        except ValueError:
            raise ValueError(
                f"{scenario}: option {self.name} must be {self._expected()}, got {text!r}"
            ) from None
        return self.check(value, scenario=scenario)

    def _expected(self) -> str:
        if self.choices is not None:
            return f"one of {list(self.choices)}"
        return {bool: "true or false", int: "an integer", float: "a finite number"}.get(
            self.type, "a string"
        )


@dataclass(frozen=True)
class ScenarioInfo:
    """A registered scenario: name, one-line description, factory, options."""

    name: str
    description: str
    factory: Callable[..., Scenario]
    options: tuple[Option, ...]

    def option(self, name: str) -> Option:
        for option in self.options:
            if option.name == name:
                return option
        raise ValueError(
            f"{self.name}: unknown option {name!r}; options are "
            f"{[o.name for o in self.options] or 'none'}"
        )


_REGISTRY: dict[str, ScenarioInfo] = {}


def _arg_help(doc: str) -> dict[str, str]:
    """``name -> help`` from a Google-style ``Args:`` section."""
    out: dict[str, str] = {}
    lines = inspect.cleandoc(doc or "").splitlines()
    inside = False
    current = None
    for line in lines:
        if line.strip() in ("Args:", "Arguments:"):
            inside = True
            continue
        if inside:
            if line and not line.startswith(" "):
                break
            match = re.match(r"^\s{4}(\w+)(?: \(.*?\))?:\s*(.*)$", line)
            if match:
                current = match.group(1)
                out[current] = match.group(2).strip()
            elif current and line.strip():
                out[current] += " " + line.strip()
    return out


def _options_of(name: str, factory: Callable[..., Scenario]) -> tuple[Option, ...]:
    hints = typing.get_type_hints(factory)
    helps = _arg_help(factory.__doc__ or "")
    out = []
    for param in inspect.signature(factory).parameters.values():
        if param.name == "seed":
            continue
        if param.kind is not inspect.Parameter.KEYWORD_ONLY or param.default is param.empty:
            raise TypeError(
                f"scenario {name}: option {param.name} must be keyword-only with a default"
            )
        hint = hints.get(param.name)
        choices = None
        if typing.get_origin(hint) is Literal:
            choices = tuple(str(c) for c in typing.get_args(hint))
            kind: type = str
        elif hint in _TYPES:
            kind = hint
        else:
            raise TypeError(
                f"scenario {name}: option {param.name} must be annotated bool, int, float, str "
                f"or a Literal of strings, got {hint!r}"
            )
        option = Option(param.name, kind, param.default, helps.get(param.name, ""), choices)
        option.check(param.default, scenario=name)
        out.append(option)
    return tuple(out)


def register(
    name: str, *, description: str | None = None
) -> Callable[[Callable[..., Scenario]], Callable[..., Scenario]]:
    """Registers a scenario factory under ``name`` (decorator).

    Args:
        name: the scenario's name (lower case, words joined by ``-``).
        description: one line; default the first line of the factory's docstring.
    """

    def decorate(factory: Callable[..., Scenario]) -> Callable[..., Scenario]:
        if name in _REGISTRY:
            raise ValueError(f"scenario {name!r} is registered twice")
        signature = inspect.signature(factory)
        if "seed" not in signature.parameters:
            raise TypeError(f"scenario {name}: the factory must take a keyword argument seed")
        first = (inspect.getdoc(factory) or "").split("\n", 1)[0].strip()
        _REGISTRY[name] = ScenarioInfo(
            name=name,
            description=description or first,
            factory=factory,
            options=_options_of(name, factory),
        )
        return factory

    return decorate


def names() -> tuple[str, ...]:
    """The registered scenario names, sorted."""
    return tuple(sorted(_REGISTRY))


def describe(name: str) -> ScenarioInfo:
    """The registered scenario ``name``; `ValueError` listing the known names otherwise."""
    info = _REGISTRY.get(name)
    if info is None:
        raise ValueError(f"unknown scenario {name!r}; known scenarios: {', '.join(names())}")
    return info


def options(name: str) -> tuple[Option, ...]:
    """The typed options of scenario ``name``, with defaults and help."""
    return describe(name).options


def _check_seed(seed: Any) -> int:
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed must be an int >= 0, got {seed!r}")
    return int(seed)


def make(name: str, *, seed: int, **overrides: Any) -> Scenario:
    """Draws scenario ``name`` with ``seed`` and options ``overrides`` (others at defaults).

    Raises:
        ValueError: unknown scenario (the known ones listed), unknown option (the scenario's
            listed), a value of the wrong type, or an impossible value (from the factory),
            before anything is drawn.
    """
    info = describe(name)
    seed = _check_seed(seed)
    values: dict[str, Any] = {}
    for key, value in overrides.items():
        values[key] = info.option(key).check(value, scenario=name)
    return info.factory(seed=seed, **values)


def parse_options(name: str, pairs: Mapping[str, str]) -> dict[str, Any]:
    """Command-line ``key=value`` strings as typed option values of scenario ``name``."""
    info = describe(name)
    return {key: info.option(key).parse(text, scenario=name) for key, text in pairs.items()}
