"""Scenarios by name: ``register`` a factory, ``make`` a scenario, list ``names`` and ``options``.

A factory is a function ``factory(*, seed: int, option: type = default, ...) -> Scenario``.
Each option is written once, in the factory's signature: its type annotation (``int``,
``float``, ``bool``, ``str`` or a ``Literal`` of strings), its allowed range where it has one
(``Annotated[float, Range(0.3, 1.5, unit="m")]``) and its default; its help comes from the
factory's docstring (``Args:`` section; the help of options several scenarios declare alike is
written once and filled in with `shared_help`). A factory whose options are a frozen
dataclass's fields says so (``register(name, options=Params)``, help from the class's
``Attributes:``) and takes them as keywords. Everything else reads them from there:
`register` wraps the factory so that every call, through `make` or directly, checks each
option's name, type and range before the factory draws anything, and records every option's
value (defaults included) in the scenario's ``options``. The factory itself checks only what
depends on several options at once (a party that fits its room).

Tags sort scenarios into sets (``register(name, tags=("hri",))``; ``names(tag="hri")``), so
that no other module keeps a list of names.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import gc
import inspect
import json
import math
import re
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Annotated, Any, Literal, TypeVar

from scenarios.scenario import Scenario, check_option

__all__ = [
    "MAX_SCENE_S",
    "Option",
    "PlaceNoise",
    "Range",
    "ScenarioInfo",
    "SceneSeconds",
    "check_options",
    "check_together",
    "check_ranges",
    "describe",
    "make",
    "names",
    "options",
    "parse_options",
    "register",
    "shared_help",
    "without_robot",
]

_TYPES = (bool, int, float, str)
# The longest scene a duration option may ask for, seconds (a day): drawing a script is work in
# proportion to its length, done before the simulation is sized.
MAX_SCENE_S = 86_400.0
_PLACEHOLDER = re.compile(r"^(\s*)\{(\w+)\}\s*$")
_Documented = TypeVar("_Documented", bound=Callable[..., Any])
_TRUE = ("true", "yes", "on", "1")
_FALSE = ("false", "no", "off", "0")


@dataclass(frozen=True)
class Range:
    """The values a number option may take: ``low <= value <= high`` (``low < value`` with
    ``above``), either end open when ``None``; ``unit`` for the message."""

    low: float | None = None
    high: float | None = None
    unit: str = ""
    above: bool = False

    def text(self) -> str:
        """The range as the options' help shows it: ``0.3-1.5``, ``> 0``, ``>= 1``."""
        if self.low is not None and self.high is not None:
            return f"{self.low:g}-{self.high:g}"
        if self.low is not None:
            return f"{'>' if self.above else '>='} {self.low:g}"
        return "any" if self.high is None else f"<= {self.high:g}"

    def check(self, value: float, *, scenario: str, name: str) -> None:
        """`ValueError` naming the scenario and the option when ``value`` is out of range."""
        check_option(
            scenario, name, value, low=self.low, high=self.high, unit=self.unit, above=self.above
        )


# Option types several scenarios declare alike.
SceneSeconds = Annotated[float, Range(0.0, MAX_SCENE_S, unit="s", above=True)]
"""A length of scene, seconds: more than 0, at most :data:`MAX_SCENE_S`."""
PlaceNoise = Annotated[float, Range(0.0, 0.3, unit="m")]
"""The standard deviation of a person's place, metres: 0 to 0.3."""


@dataclass(frozen=True)
class Option:
    """One option of a scenario.

    Attributes:
        name: keyword name.
        type: ``bool``, ``int``, ``float`` or ``str``.
        default: the default value.
        help: one line (with the unit).
        choices: the allowed values of a ``str`` option with a fixed set, else ``None``.
        range: the allowed values of a number option, else ``None``.
    """

    name: str
    type: type
    default: Any
    help: str = ""
    choices: tuple[str, ...] | None = None
    range: Range | None = None

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
        if self.range is not None:
            self.range.check(value, scenario=scenario, name=self.name)
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
            elif kind in (int, float):  # in ASCII: int('٣') would be 3
                if not text.isascii():
                    raise ValueError
                value = kind(text)
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
    """A registered scenario: name, one-line description, factory, options, tags, and the
    options that put the Directions Robot in its scene (``robot``; None: it has no place for
    the robot)."""

    name: str
    description: str
    factory: Callable[..., Scenario]
    options: tuple[Option, ...]
    tags: frozenset[str] = frozenset()
    robot: Mapping[str, Any] | None = None
    params: type | None = None  # the options' dataclass, when they are declared by one

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
    """``name -> help`` from a Google-style ``Args:`` (or ``Attributes:``) section."""
    out: dict[str, str] = {}
    lines = inspect.cleandoc(doc or "").splitlines()
    inside = False
    current = None
    for line in lines:
        if line.strip() in ("Args:", "Arguments:", "Attributes:"):
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


def shared_help(**blocks: Mapping[str, str]) -> Callable[[_Documented], _Documented]:
    """Writes the help of options several scenarios declare alike, kept in one place, into a
    factory's (or an options class's) docstring: its line ``{key}`` becomes a line
    ``name: help`` for each entry of ``blocks[key]``, indented as the placeholder was. Apply it
    below `register`, which reads the docstring; each option's range and default stay in the
    scenario's own declaration.

    Raises:
        ValueError: a placeholder with no block, or a block with no placeholder.
    """

    def fill(target: _Documented) -> _Documented:
        lines = []
        used = set()
        for line in (target.__doc__ or "").split("\n"):
            match = _PLACEHOLDER.match(line)
            if match is None:
                lines.append(line)
                continue
            indent, key = match.groups()
            if key not in blocks:
                raise ValueError(f"{target.__name__}: no shared help for {{{key}}}")
            used.add(key)
            lines += [f"{indent}{name}: {text}" for name, text in blocks[key].items()]
        if used != set(blocks):
            raise ValueError(f"{target.__name__}: no placeholder for {sorted(set(blocks) - used)}")
        target.__doc__ = "\n".join(lines)
        return target

    return fill


def _declared(source: Callable[..., Any] | type) -> list[tuple[str, Any, Any]]:
    """``(name, annotation, default)`` of each option ``source`` declares: the keyword-only
    parameters of a factory but ``seed``, or the fields of a frozen dataclass."""
    hints = typing.get_type_hints(source, include_extras=True)
    if dataclasses.is_dataclass(source):
        return [
            (f.name, hints.get(f.name), f.default) for f in dataclasses.fields(source) if f.init
        ]
    out = []
    for param in inspect.signature(source).parameters.values():
        if param.name == "seed" or param.kind is inspect.Parameter.VAR_KEYWORD:
            continue
        if param.kind is not inspect.Parameter.KEYWORD_ONLY or param.default is param.empty:
            raise TypeError(f"option {param.name} must be keyword-only with a default")
        out.append((param.name, hints.get(param.name), param.default))
    return out


def _options_of(name: str, source: Callable[..., Any] | type) -> tuple[Option, ...]:
    helps = _arg_help(source.__doc__ or "")
    out = []
    try:
        declared = _declared(source)
    except TypeError as exc:
        raise TypeError(f"scenario {name}: {exc}") from None
    for key, hint, default in declared:
        bounds = None
        if typing.get_origin(hint) is Annotated:
            hint, *extras = typing.get_args(hint)
            bounds = next((e for e in extras if isinstance(e, Range)), None)
        choices = None
        if typing.get_origin(hint) is Literal:
            choices = tuple(str(c) for c in typing.get_args(hint))
            kind: type = str
        elif hint in _TYPES:
            kind = hint
        else:
            raise TypeError(
                f"scenario {name}: option {key} must be annotated bool, int, float, str "
                f"or a Literal of strings, got {hint!r}"
            )
        if default is dataclasses.MISSING:
            raise TypeError(f"scenario {name}: option {key} must have a default")
        if bounds is not None and kind not in (int, float):
            raise TypeError(f"scenario {name}: option {key} has a Range but is not a number")
        text = helps.get(key, "")
        if bounds is not None:  # the range is shown from the annotation, never typed twice
            end = "." if text.endswith(".") else ""
            text = f"{text.rstrip('.')} ({bounds.text()}){end}".lstrip()
        option = Option(key, kind, default, text, choices, bounds)
        option.check(default, scenario=name)
        out.append(option)
    return tuple(out)


def check_ranges(scenario: str, params: Any) -> None:
    """Checks each field of the dataclass instance ``params`` against its ``Range``
    annotation; `ValueError` naming ``scenario`` and the first field out of range."""
    for key, bounds in _ranges(type(params)):
        bounds.check(getattr(params, key), scenario=scenario, name=key)


@functools.cache
def _ranges(source: type) -> tuple[tuple[str, Range], ...]:
    """``(field, Range)`` of each ``Range`` annotating a field of dataclass ``source``, in
    field order: read once per class (`typing.get_type_hints` takes a millisecond, and a
    scenario's options are checked each time one is made)."""
    out = []
    for key, hint, _ in _declared(source):
        if typing.get_origin(hint) is Annotated:
            out += [(key, e) for e in typing.get_args(hint)[1:] if isinstance(e, Range)]
    return tuple(out)


def _check_options_of(
    name: str, declared: tuple[Option, ...], given: Mapping[str, Any]
) -> dict[str, Any]:
    """``given`` checked against the options ``declared`` (names, types, ranges)."""
    by_name = {o.name: o for o in declared}
    out = {}
    for key, value in given.items():
        if key not in by_name:
            raise ValueError(
                f"{name}: unknown option {key!r}; options are {list(by_name) or 'none'}"
            )
        out[key] = by_name[key].check(value, scenario=name)
    return out


def check_options(name: str, given: Mapping[str, Any]) -> dict[str, Any]:
    """Every option of scenario ``name``: the values ``given``, checked (name, type, range),
    and the defaults of the others, in declaration order.

    Raises:
        ValueError: an unknown option (the scenario's listed), a value of the wrong type or out
            of its range, naming the scenario and the option.
    """
    info = describe(name)
    checked = _check_options_of(name, info.options, given)
    return {o.name: checked.get(o.name, o.default) for o in info.options}


def check_together(name: str, values: Mapping[str, Any]) -> None:
    """`ValueError` for options of scenario ``name``, each in its range (`check_options`), that
    do not go together (a crowd its floor cannot hold), as its options' dataclass checks them
    (its ``check(name)``) before anything is drawn; nothing to check for other scenarios. A
    party that fits on paper may still find no floor once drawn (`scenarios.mingle.NoFloorError`,
    raised by `make`)."""
    params = describe(name).params
    check = getattr(params, "check", None)
    if params is not None and check is not None:
        params(**values).check(name)


def register(
    name: str,
    *,
    description: str | None = None,
    tags: tuple[str, ...] = (),
    options: type | None = None,
    robot: Mapping[str, Any] | None = None,
) -> Callable[[Callable[..., Scenario]], Callable[..., Scenario]]:
    """Registers a scenario factory under ``name`` (decorator).

    Args:
        name: the scenario's name (lower case, words joined by ``-``).
        description: one line; default the first line of the factory's docstring.
        tags: the sets the scenario belongs to (``names(tag=...)``).
        options: a frozen dataclass whose fields are the options, when the factory takes them
            as ``**options`` rather than in its signature.
        robot: the options that put the Directions Robot in the scene (``{}`` when it is always
            there); None when the scene has no place for it. The robot's environments
            (`sim.envs`) are made for every scenario that has one.

    Returns:
        The decorator, which returns the factory wrapped: every call checks its options and
        records them all in the scenario it returns.
    """

    def decorate(factory: Callable[..., Scenario]) -> Callable[..., Scenario]:
        if name in _REGISTRY:
            raise ValueError(f"scenario {name!r} is registered twice")
        signature = inspect.signature(factory)
        if "seed" not in signature.parameters:
            raise TypeError(f"scenario {name}: the factory must take a keyword argument seed")
        first = (inspect.getdoc(factory) or "").split("\n", 1)[0].strip()

        @functools.wraps(factory)
        def checked(*, seed: int, **given: Any) -> Scenario:
            seed = _check_seed(seed)
            values = check_options(name, given)
            with _collector_paused():
                made = factory(seed=seed, **values)
            # What the factory recorded besides its options (what it drew) follows them.
            drawn = {k: v for k, v in made.options.items() if k not in values}
            return dataclasses.replace(made, options={**values, **drawn})

        declared = _options_of(name, factory if options is None else options)
        checked.__signature__ = signature.replace(  # type: ignore[attr-defined]
            parameters=[
                inspect.Parameter("seed", inspect.Parameter.KEYWORD_ONLY, annotation=int),
                *(
                    inspect.Parameter(
                        o.name, inspect.Parameter.KEYWORD_ONLY, default=o.default, annotation=o.type
                    )
                    for o in declared
                ),
            ]
        )
        _REGISTRY[name] = ScenarioInfo(
            name=name,
            description=description or first,
            factory=checked,
            options=declared,
            tags=frozenset(tags),
            robot=None
            if robot is None
            else MappingProxyType(_check_options_of(name, declared, robot)),
            params=options,
        )
        return checked

    return decorate


@contextlib.contextmanager
def _collector_paused() -> typing.Iterator[None]:
    """Python's cyclic garbage collector paused (if it runs) while a scenario is drawn: a
    script is tens of thousands of small objects made at once and none of them in a cycle, so
    the collections their making sets off scan them again and again for nothing (a sixth of
    ``mingle``'s making). Reference counting frees memory as always meanwhile."""
    if not gc.isenabled():
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


def names(*, tag: str | None = None) -> tuple[str, ...]:
    """The registered scenario names, sorted; with ``tag``, those tagged so, in the order they
    were registered (the order their module lists them)."""
    if tag is None:
        return tuple(sorted(_REGISTRY))
    return tuple(name for name, info in _REGISTRY.items() if tag in info.tags)


def describe(name: str) -> ScenarioInfo:
    """The registered scenario ``name``; `ValueError` listing the known names otherwise."""
    info = _REGISTRY.get(name)
    if info is None:
        raise ValueError(f"unknown scenario {name!r}; known scenarios: {', '.join(names())}")
    return info


def without_robot(name: str) -> str:
    """Why a scene of scenario ``name`` has no Directions Robot, and what puts one in it:
    ``"scenario concourse has no place for the robot"``, or ``"scenario mingle has none with
    these options (robot=true puts it there)"``."""
    robot = describe(name).robot
    if robot is None:
        return f"scenario {name} has no place for the robot"
    given = ", ".join(
        f"{key}={value if isinstance(value, str) else json.dumps(value)}"
        for key, value in robot.items()
    )
    return f"scenario {name} has none with these options ({given} puts it there)"


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
            listed), a value of the wrong type or out of its range, or an impossible
            combination (from the factory), before anything is drawn.
    """
    return describe(name).factory(seed=seed, **overrides)


def parse_options(name: str, pairs: Mapping[str, str]) -> dict[str, Any]:
    """Command-line ``key=value`` strings as typed option values of scenario ``name``."""
    info = describe(name)
    return {key: info.option(key).parse(text, scenario=name) for key, text in pairs.items()}
