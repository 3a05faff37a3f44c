"""The detector protocol and the one registry of detectors: built-ins, plugins, entry points.

**The protocol.** A detector is any object with ``predict(frames)`` returning one partition per
frame, in order: a sequence of groups, each a tuple of person ids of that frame, that together
hold every id of the frame exactly once (people alone are groups of one). It may also have
``fit(frames)`` (annotated frames; it trains in place and returns ``self``, as a scikit-learn
estimator does). :class:`Detector` states it as a `typing.Protocol`; nothing needs to inherit
from it.

**The registry.** One table of detectors by name, for the command line (``--detector``), the
stress tests, the benchmarks and your code::

    make_detector("gcff", stride=0.6)            # a registered name, with its options
    make_detector("reform", model="m.skops")     # a model written by `reform-sim train`
    make_detector("mylab.detectors:make")        # a plugin: module path and factory, imported

Names come from :func:`register_detector` (the built-ins ``majority``, ``gcff`` and
``reform``) and from the entry-point group :data:`ENTRY_POINT_GROUP` of installed packages
(``[project.entry-points."reform_sim.detectors"] mine = "mylab.detectors:make"``), read when a
name is looked up (a package installed meanwhile is seen); nothing of theirs is imported until
their detector is made. A factory is called with the options and must return an object with a
callable ``predict``; an object that already has one is used as it is.

**Memory.** A detector may say what one frame costs it: ``frame_bytes(n_people)``, the bytes it
takes at its peak to predict a frame of that many people (those whose memory grows with the
pairs of people say).
:func:`check_frame_memory` refuses, before any frame is predicted, frames that would take more
than a limit, naming the largest frame, what it needs and how many people fit.

**Checked runs.** :func:`run_detector` calls ``predict`` and :func:`check_predictions` checks
what came back; whatever goes wrong inside a detector becomes one :class:`DetectorError` line
naming the detector and, where it can, the frame.

Pure Python and numpy: the built-in detectors (scikit-learn) are imported when one is made, so
that importing this module to list the names stays light.
"""

from __future__ import annotations

import copy
import importlib
import importlib.metadata
import inspect
import math
import numbers
import os
import reprlib
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from reform.deadline import STUCK_GRACE_S, DeadlineExpired, within

if TYPE_CHECKING:
    from reform.frame import Frame, Group

__all__ = [
    "ENTRY_POINT_GROUP",
    "Detector",
    "DetectorError",
    "DetectorInfo",
    "IMPORT_TIMEOUT_S",
    "PREDICT_TIMEOUT_S",
    "PREDICT_TIMEOUT_S_PER_PAIR",
    "FrameTooLarge",
    "Option",
    "check_frame_memory",
    "check_predictions",
    "frame_memory",
    "builtin_names",
    "detector_info",
    "detector_names",
    "detector_options",
    "fit_detector",
    "make_detector",
    "predict_deadline",
    "prepare_detector",
    "register_detector",
    "run_detector",
]

ENTRY_POINT_GROUP = "reform_sim.detectors"  # installed packages add detectors by name here
_SPEC_FORM = "package.module:factory"
# Deadlines on a detector's code, unless the caller gives one (``--detector-timeout``): generous,
# about a thousand times what the built-ins take (milliseconds a frame of twenty people).
IMPORT_TIMEOUT_S = 60.0  # seconds to import a detector's module, and again to call its factory
PREDICT_TIMEOUT_S = 5.0  # seconds a frame, plus PREDICT_TIMEOUT_S_PER_PAIR for each pair in it
PREDICT_TIMEOUT_S_PER_PAIR = 0.05  # seconds a frame for each pair of people in it
_TIMEOUT_HINT = "give it longer with --detector-timeout DURATION"


def _stuck(what: str, seconds: float) -> str:
    """The line `reform.deadline.hard_stops` says of ``what`` (``"detector 'x': ... (predict
    on 12 frames)"``) still running in compiled code after its deadline of ``seconds``."""
    return (
        f"{what} did not finish within {seconds:g} s and had not returned to Python "
        f"{STUCK_GRACE_S:g} s later (stuck in compiled code, where it cannot be stopped): the "
        f"process was ended; {_TIMEOUT_HINT}"
    )


class DetectorError(ValueError):
    """A detector that cannot be found, made or run, or that broke the protocol; one line."""


@runtime_checkable
class Detector(Protocol):
    """What every detector is: ``predict(frames)`` -> one partition per frame.

    ``predict`` takes a sequence of `reform.Frame` and returns, for each frame in order, a
    sequence of groups (tuples of person ids) holding every id of that frame exactly once,
    singletons included. A detector that learns also has ``fit(frames)``, training in place on
    annotated frames and returning ``self``; the protocol does not require it, and callers that
    train (`fit_detector`) skip detectors without one.
    """

    def predict(self, frames: Sequence[Frame]) -> Sequence[Sequence[Group]]:
        """One partition of each frame's ids, in the frames' order."""
        ...


OPTION_TYPES = ("float", "int", "str", "bool", "path")  # what an Option's value may be
LEANS = ("", "low", "high")  # the end of an option's grid that groups fewer people together
NEEDS = ("", "dataset", "training")  # what a detector must be given before it predicts


@dataclass(frozen=True)
class Option:
    """One option of a catalogued detector, declared once: the command line (``--option
    NAME=VALUE``), ``--help``, the registry's checks and the tuning searches read it from here.

    Attributes:
        name: the factory's keyword argument.
        type: one of :data:`OPTION_TYPES`.
        default: its value when not given (None: not given means the factory's own choice, said
            in ``help``).
        help: one line on what it does.
        unit: the unit of a number (``"m"``, ``"m²"``, ``"rad"``), or ``""`` for a pure number.
        low: the smallest value accepted (numbers), or None.
        high: the largest value accepted (numbers), or None.
        choices: the values accepted (``str``), or ``()`` for any.
        grid: values a settings search tries (``reform-sim tune``), or ``()`` when it is not tuned.
        lean: the end of ``grid`` that groups fewer people together (``"low"`` or ``"high"``),
            or ``""`` when neither does: among the settings a search on a venue twin cannot
            tell apart, it takes the value nearest that end (`sim.twins.tune`).
    """

    name: str
    type: str
    default: Any
    help: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] = ()
    grid: tuple[Any, ...] = ()
    lean: str = ""

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ValueError(f"an option's name must be an identifier, got {self.name!r}")
        if self.lean not in LEANS:
            raise ValueError(
                f"option {self.name!r}: lean must be one of {LEANS}, got {self.lean!r}"
            )
        if self.type not in OPTION_TYPES:
            raise ValueError(
                f"option {self.name!r}: type must be one of {', '.join(OPTION_TYPES)}, "
                f"got {self.type!r}"
            )

    def expects(self) -> str:
        """What the option accepts: ``"a float in m from 0.01 to 10"``."""
        article = "an" if self.type == "int" else "a"
        text = f"{article} {self.type}" + (f" in {self.unit}" if self.unit else "")
        if self.choices:
            return f"{text}, one of {', '.join(self.choices)}"
        if self.low is not None and self.high is not None:
            return f"{text} from {_number(self.low)} to {_number(self.high)}"
        if self.low is not None:
            return f"{text} of at least {_number(self.low)}"
        if self.high is not None:
            return f"{text} of at most {_number(self.high)}"
        return text

    def describe(self) -> str:
        """``"stride: a float in m from 0.01 to 10, default 0.7; help"``: a line of ``--help``."""
        default = "" if self.default is None else f", default {self.default!s}"
        return f"{self.name}: {self.expects()}{default}; {self.help}"

    def parse(self, detector: str, text: str) -> Any:
        """The value of ``text`` (a command line's string), checked by :meth:`check`."""
        parsers: dict[str, Callable[[str], Any]] = {
            "float": float,
            "int": int,
            "str": str,
            "path": str,
            "bool": _parse_bool,
        }
        try:
            if self.type in ("float", "int") and not text.isascii():  # int('٣') would be 3
                raise ValueError
            value = parsers[self.type](text)
        except ValueError:
            raise DetectorError(
                f"detector {detector!r}: option {self.name} expects {self.expects()}, got {text!r}"
            ) from None
        return self.check(detector, value)

    def check(self, detector: str, value: Any) -> Any:
        """``value`` when it is of the option's type and inside its range; else DetectorError
        naming the detector, the option, what is accepted and what came."""
        if value is None:
            return value
        if self.type in ("float", "int"):
            number = isinstance(value, numbers.Real) and not isinstance(value, bool)
            ok = (
                number
                and type(value).__name__ != "bool_"
                and math.isfinite(float(value))
                and (self.type == "float" or float(value) == int(value))
                and (self.low is None or value >= self.low)
                and (self.high is None or value <= self.high)
            )
            if ok:
                return int(value) if self.type == "int" else float(value)
        elif self.type == "bool":
            if isinstance(value, bool) or type(value).__name__ == "bool_":  # numpy's too
                return bool(value)
        elif self.type == "path":
            if isinstance(value, (str, os.PathLike)):
                return value
        elif isinstance(value, str) and (not self.choices or value in self.choices):
            return value
        raise DetectorError(
            f"detector {detector!r}: option {self.name} expects {self.expects()}, "
            f"got {_describe(value)}"
        )


def _number(value: float) -> str:
    """A bound as people write it: ``0.01``, ``10``, ``1,048,576``."""
    if float(value).is_integer() and abs(value) < 1e15:
        return f"{int(value):,}"
    return f"{value:g}"


def _parse_bool(text: str) -> bool:
    words = {"true": True, "yes": True, "1": True, "false": False, "no": False, "0": False}
    if text.strip().lower() not in words:
        raise ValueError(text)
    return words[text.strip().lower()]


@dataclass(frozen=True)
class DetectorInfo:
    """One detector the registry knows.

    Attributes:
        name: the name it is looked up by (a ``package.module:factory`` spec for a plugin named
            by its path).
        help: one line on what it is.
        factory: ``factory(**options) -> detector``, or where to import it from
            (``"package.module:attribute"``), imported when the detector is made.
        source: where the name comes from: ``"built-in"``, ``"registered"``, ``"import path"``
            or the entry point and the package that declares it.
        options: its options, declared once (:class:`Option`); ``()`` for a detector whose
            options are only its factory's signature (a plugin's).
        citation: the paper it implements (authors, title, venue, year), or ``""``.
        needs: what it must be given before it predicts (:data:`NEEDS`): ``""`` nothing,
            ``"dataset"`` the dataset it runs on (its ``for_dataset(dataset)`` returns the
            detector for it, e.g. one with the settings the dataset ships), ``"training"``
            annotated frames to ``fit`` on (never the frames it is scored on).
    """

    name: str
    help: str
    factory: Callable[..., Any] | str
    source: str
    options: tuple[Option, ...] = ()
    citation: str = ""
    needs: str = ""

    @property
    def runs_from_file(self) -> bool:
        """Whether it is made from a file it was trained into: an option naming a file
        (``type`` ``"path"``) with no default."""
        return any(o.type == "path" and o.default is None for o in self.options)

    def option(self, name: str) -> Option:
        """The declared option ``name``; DetectorError listing the accepted ones."""
        for option in self.options:
            if option.name == name:
                return option
        accepted = ", ".join(o.name for o in self.options) or "none"
        raise DetectorError(
            f"detector {self.name!r} has no option {name!r}; its options: {accepted}"
        )


_REGISTRY: dict[str, DetectorInfo] = {}


def _check_name(name: Any) -> str:
    if not isinstance(name, str) or not name or ":" in name or name != "".join(name.split()):
        raise DetectorError(
            f"a detector name must be a non-empty word without ':' or spaces (':' marks "
            f"{_SPEC_FORM}), got {name!r}"
        )
    return name


def _parse_spec(spec: str) -> tuple[str, str]:
    """``"package.module:attribute"`` -> (module, attribute); DetectorError when malformed."""
    module, _, attribute = spec.partition(":")
    parts = [*module.split("."), *attribute.split(".")]
    if not all(part.isidentifier() for part in parts):
        raise DetectorError(f"a detector path must read {_SPEC_FORM}, got {spec!r}")
    return module, attribute


def _register(
    name: str,
    factory: Any,
    *,
    help: str,  # noqa: A002
    source: str,
    options: Sequence[Option] = (),
    citation: str = "",
    needs: str = "",
) -> None:
    _check_name(name)
    if needs not in NEEDS:
        raise DetectorError(f"detector {name!r}: needs must be one of {NEEDS}, got {needs!r}")
    options = tuple(options)
    if not all(isinstance(option, Option) for option in options):
        raise DetectorError(f"detector {name!r}: options must be reform.detectors.Option")
    if len({option.name for option in options}) != len(options):
        raise DetectorError(f"detector {name!r}: an option is declared twice")
    if not isinstance(help, str) or not help.strip() or "\n" in help.strip():
        raise DetectorError(f"detector {name!r}: help must be one line of text, got {help!r}")
    if isinstance(factory, str):
        _parse_spec(factory)
    elif not callable(factory):
        raise DetectorError(
            f"detector {name!r}: the factory must be callable or a {_SPEC_FORM} path, "
            f"got {_describe(factory)}"
        )
    if name in _REGISTRY:
        raise DetectorError(
            f"detector {name!r} is registered twice (it is already {_REGISTRY[name].source})"
        )
    _REGISTRY[name] = DetectorInfo(
        name=name,
        help=help.strip(),
        factory=factory,
        source=source,
        options=options,
        citation=citation,
        needs=needs,
    )


def register_detector(
    name: str,
    factory: Callable[..., Any] | str | None = None,
    *,
    help: str | None = None,  # noqa: A002 - argparse's word
    options: Sequence[Option] = (),
    citation: str = "",
    needs: str = "",
) -> Any:
    """Registers ``factory(**options) -> detector`` under ``name``; also a decorator.

    ``register_detector("pairs", make_pairs, help="...")``, or ``@register_detector("pairs",
    help="...")`` above the factory. The factory's keyword parameters are the detector's
    options (`make_detector` checks them against its signature); a ``"package.module:attr"``
    string is imported when the detector is first made.

    Args:
        name: a word without ``:`` or spaces.
        factory: the factory (omitted: returns a decorator).
        help: one line on the detector (default: the first line of the factory's docstring,
            else its import path).
        options: its options declared (:class:`Option`: type, default, range, unit, help); the
            command line and ``--help`` show them, and `make_detector` checks values against
            them. ``()``: the factory's signature alone says which options exist.
        citation: the paper the detector implements.
        needs: ``"dataset"`` or ``"training"`` (see :class:`DetectorInfo`), ``""`` for neither.

    Returns:
        The factory (or, without one, the decorator that registers and returns it).

    Raises:
        DetectorError: a name registered twice, a malformed name, help or factory.
    """
    if factory is None:

        def decorate(function: Callable[..., Any]) -> Callable[..., Any]:
            _register(
                name,
                function,
                help=_help_of(function, help),
                source="registered",
                options=options,
                citation=citation,
                needs=needs,
            )
            return function

        return decorate
    _register(
        name,
        factory,
        help=_help_of(factory, help),
        source="registered",
        options=options,
        citation=citation,
        needs=needs,
    )
    return factory


def _help_of(factory: Any, given: str | None) -> Any:
    """``given``, else the first line of the factory's docstring, else its import path (what
    `_register` checks when the factory is malformed)."""
    if given is not None:
        return given
    if isinstance(factory, str):
        return f"plugin {factory}"
    doc = (getattr(factory, "__doc__", None) or "").strip()
    if doc:
        return doc.splitlines()[0].strip()
    return f"plugin {_import_path(factory)}"


def _import_path(factory: Any) -> str:
    """Where a factory is imported from: ``"module:qualname"`` (its string for a path)."""
    if isinstance(factory, str):
        return factory.split("[", 1)[0].strip()
    module = getattr(factory, "__module__", None) or "?"
    return f"{module}:{getattr(factory, '__qualname__', type(factory).__name__)}"


def _same_package(registered: DetectorInfo, entry: importlib.metadata.EntryPoint) -> bool:
    """Whether a registration and an entry point come from one package: the entry point's module
    registers its own detector when imported (as the extending guide shows)."""
    module = entry.value.split(":", 1)[0].strip()
    return _import_path(registered.factory).split(":", 1)[0] == module


def _entry_points() -> dict[str, list[importlib.metadata.EntryPoint]]:
    """The installed packages' detectors by name, as installed now: a package installed or
    removed since the last lookup is seen. They are read again only when the search path or
    the modification time of one of its folders has changed (installing or removing a package
    adds or removes its metadata folder there): reading every installed package's metadata
    takes some 20 ms, and a run making detectors by the hundred would spend seconds on it.
    Names with ``:`` could never be looked up and are left out."""
    global _installed
    key = tuple((folder or os.getcwd(), _modified(folder)) for folder in sys.path)
    if _installed is not None and _installed[0] == key:
        return _installed[1]
    found: dict[str, list[importlib.metadata.EntryPoint]] = {}
    for entry in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        if ":" not in entry.name:
            found.setdefault(entry.name, []).append(entry)
    _installed = (key, found)
    return found


# The last `_entry_points` read: the search path's folders (the working folder for "") with
# their modification times, and what was found then.
_installed: tuple[tuple[tuple[str, int | None], ...], dict[str, list[Any]]] | None = None


def _modified(folder: str) -> int | None:
    """A search-path entry's modification time, nanoseconds (None: it does not exist)."""
    try:
        return os.stat(folder or ".").st_mtime_ns
    except OSError:
        return None


def _entry_source(entry: importlib.metadata.EntryPoint) -> str:
    dist = getattr(entry, "dist", None)
    package = f" of {dist.name} {dist.version}" if dist is not None else ""
    return f"entry point {entry.name} = {entry.value}{package}"


def detector_names() -> tuple[str, ...]:
    """Every detector name: the registered ones and those of installed packages, sorted."""
    return tuple(sorted(set(_REGISTRY) | set(_entry_points())))


def builtin_names(*, needs: Sequence[str] = NEEDS) -> tuple[str, ...]:
    """The catalogue's built-in detectors that run with their declared defaults (none read from
    a model file, as ``reform`` is), whose :attr:`DetectorInfo.needs` is among ``needs``: what
    ``benchmark --detector all`` and ``stress --detector all`` run."""
    out = []
    for name in sorted(_REGISTRY):
        info = _REGISTRY[name]
        if info.source != "built-in" or info.needs not in needs:
            continue
        if any(o.default is None and o.type == "path" for o in info.options):
            continue  # a detector read from a trained model file
        out.append(name)
    return tuple(out)


def detector_options(name: str) -> tuple[Option, ...]:
    """The declared options of the detector ``name`` (``()`` for one that declares none)."""
    return detector_info(name).options


def detector_info(name_or_path: str) -> DetectorInfo:
    """What ``name_or_path`` names: a registered detector, an installed package's, or a plugin
    given by its ``package.module:factory`` path (not imported yet).

    Raises:
        DetectorError: an unknown name (listing the known ones), a name that two sources
            register, or a malformed path.
    """
    if not isinstance(name_or_path, str):
        raise DetectorError(
            f"a detector is named by a string (a name or {_SPEC_FORM}), got "
            f"{_describe(name_or_path)}"
        )
    if ":" in name_or_path:
        _parse_spec(name_or_path)
        return DetectorInfo(
            name=name_or_path,
            help=f"plugin {name_or_path}",
            factory=name_or_path,
            source="import path",
        )
    registered = _REGISTRY.get(name_or_path)
    installed = _entry_points().get(name_or_path, [])
    if registered is not None:  # imported from its own entry point: one source, not two
        installed = [e for e in installed if not _same_package(registered, e)]
    sources = ([registered.source] if registered else []) + [_entry_source(e) for e in installed]
    if len(sources) > 1:
        raise DetectorError(
            f"detector {name_or_path!r} is registered twice: {'; '.join(sources)} "
            "(uninstall one of the packages)"
        )
    if registered is not None:
        return registered
    if installed:
        (entry,) = installed
        return DetectorInfo(
            name=name_or_path,
            help=f"from {_entry_source(entry)}",
            factory=entry.value.split("[", 1)[0].strip(),  # extras ("mod:attr [extra]") unused
            source=_entry_source(entry),
        )
    raise DetectorError(
        f"unknown detector {name_or_path!r}; known detectors: {', '.join(detector_names())} "
        f"(or give a plugin as {_SPEC_FORM})"
    )


def _one_line(exc: BaseException) -> str:
    """``"Type: message"`` of an exception, its message on one line."""
    message = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {message}" if message else type(exc).__name__


def _describe(value: Any) -> str:
    if value is None:
        return "None"
    return f"a {type(value).__name__} ({reprlib.repr(value)})"


def _import(name: str, spec: str, deadline_s: float) -> Any:
    """The object ``spec`` (``package.module:attribute``) names, imported within
    ``deadline_s`` seconds."""
    module_name, attribute = _parse_spec(spec)
    try:
        stuck = _stuck(f"detector {name!r}: the import of module {module_name!r}", deadline_s)
        module = within(deadline_s, importlib.import_module, module_name, stuck=stuck)
    except DeadlineExpired as exc:
        raise DetectorError(
            f"detector {name!r}: the detector did not finish within {exc.seconds:g} s (import "
            f"of module {module_name!r}); {_TIMEOUT_HINT}"
        ) from None
    except _RAISED as exc:  # the plugin's own code runs here (a sys.exit too): its error
        hint = ""
        if isinstance(exc, ModuleNotFoundError) and module_name.startswith(str(exc.name)):
            hint = " (is the package installed, or its folder on PYTHONPATH?)"
        raise DetectorError(
            f"detector {name!r}: cannot import module {module_name!r}: {_one_line(exc)}{hint}"
        ) from exc
    value: Any = module
    for part in attribute.split("."):
        try:
            value = getattr(value, part)
        except AttributeError:
            raise DetectorError(
                f"detector {name!r}: module {module_name!r} has no attribute {attribute!r}"
            ) from None
    return value


def _has_predict(value: Any) -> bool:
    return not isinstance(value, type) and callable(getattr(value, "predict", None))


def _check_options(name: str, factory: Callable[..., Any], options: Mapping[str, Any]) -> None:
    """The options against the factory's signature: none unknown, none required missing."""
    try:
        parameters = list(inspect.signature(factory).parameters.values())
    except (TypeError, ValueError):  # no signature to read (a builtin): the call will tell
        return
    named = [
        p
        for p in parameters
        if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    ]
    accepted = ", ".join(p.name for p in named) or "none"
    if not any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters):
        unknown = [key for key in options if key not in {p.name for p in named}]
        if unknown:
            raise DetectorError(
                f"detector {name!r} has no option {unknown[0]!r}; its options: {accepted}"
            )
    missing = [
        p.name for p in named if p.default is inspect.Parameter.empty and p.name not in options
    ]
    if missing:
        raise DetectorError(
            f"detector {name!r} needs the option {missing[0]}= (its options: {accepted})"
        )


def make_detector(
    name_or_path: str, *, deadline_s: float | None = None, **options: Any
) -> Detector:
    """A detector ready to ``predict`` (or to ``fit``), made by the factory its name names.

    Args:
        name_or_path: a name of :func:`detector_names` or a plugin's
            ``package.module:factory`` path (imported now).
        deadline_s: seconds its module may take to import, and its factory to return
            (default :data:`IMPORT_TIMEOUT_S`).
        **options: the factory's keyword arguments, e.g. ``stride=0.6`` for ``gcff``
            (metres), ``model="m.skops"`` for ``reform``.

    Returns:
        What the factory returned: an object with a callable ``predict``. An object the name
        points at that already has one (a detector rather than a factory) is returned as it is.

    Raises:
        DetectorError: one line: an unknown name, a plugin that does not import or has no such
            attribute, an unknown or missing option, a factory that raises, an object without
            a callable ``predict``; an import or a factory that did not finish within
            ``deadline_s``.
    """
    deadline_s = IMPORT_TIMEOUT_S if deadline_s is None else deadline_s
    info = detector_info(name_or_path)
    name = info.name
    if info.options:  # the declared defaults, then what was given, each checked
        given = {key: info.option(key).check(name, value) for key, value in options.items()}
        defaults = {o.name: o.default for o in info.options if o.default is not None}
        options = {**defaults, **given}
    if isinstance(info.factory, str):
        label, target = info.factory, _import(name, info.factory, deadline_s)
    else:
        label, target = getattr(info.factory, "__qualname__", repr(info.factory)), info.factory
    if _has_predict(target):
        if options:
            raise DetectorError(
                f"detector {name!r}: {label} is a detector, not a factory, so it takes no "
                f"options (got {', '.join(options)})"
            )
        return target
    if not callable(target):
        raise DetectorError(
            f"detector {name!r}: {label} is {_describe(target)}, neither a factory nor an "
            "object with a callable predict(frames)"
        )
    _check_options(name, target, options)
    try:
        stuck = _stuck(f"detector {name!r}: its factory {label}", deadline_s)
        detector = within(deadline_s, target, stuck=stuck, **options)
    except DeadlineExpired as exc:
        raise DetectorError(
            f"detector {name!r}: the detector did not finish within {exc.seconds:g} s (build: "
            f"its factory {label}); {_TIMEOUT_HINT}"
        ) from None
    except DetectorError:
        raise
    except _RAISED as exc:  # the factory is the plugin's code (a sys.exit too)
        raise DetectorError(f"detector {name!r} could not be made: {_one_line(exc)}") from exc
    if not _has_predict(detector):
        raise DetectorError(
            f"detector {name!r}: its factory {label} returned {_describe(detector)}, which has "
            "no callable predict(frames)"
        )
    return detector


class FrameTooLarge(DetectorError):
    """A frame that would take a detector more memory than the run may have (one line)."""


def frame_memory(detector: Any, n_people: int) -> int | None:
    """Bytes ``detector`` takes at its peak to predict one frame of ``n_people``, as its
    ``frame_bytes(n_people)`` says; None for a detector that does not say (or says nonsense)."""
    method = getattr(detector, "frame_bytes", None)
    if not callable(method):
        return None
    try:
        needed = method(int(n_people))
    except _RAISED:  # someone's code: a detector that cannot say is one that does not
        return None
    if isinstance(needed, bool) or not isinstance(needed, numbers.Real) or not needed >= 0:
        return None
    return math.ceil(needed) if math.isfinite(needed) else None


def check_frame_memory(
    name: str,
    detector: Any,
    frames: Sequence[Frame],
    *,
    limit: int,
    limit_text: str,
    source: str = "",
    hint: str = "",
) -> None:
    """Refuses, before any frame is predicted, frames too large for the memory a run may take.

    The largest frame (the most people; the first of them) is sized with :func:`frame_memory`;
    a detector that does not say what a frame costs is not checked. A detector whose
    ``max_frame_bytes`` is below ``limit`` is held to that (it refuses larger frames itself).

    Args:
        name: the detector's name, for the message.
        detector: the detector that would predict the frames.
        frames: the frames.
        limit: bytes one frame may take.
        limit_text: what sets the limit, as the message names it (``"--max-memory 8 GiB"``).
        source: where the frames come from (a file, a dataset), for the message.
        hint: what to do instead, appended to the message.

    Raises:
        FrameTooLarge: naming the frame, its people, the memory it needs, the limit and the
            most people a frame may hold within it.
    """
    from reform.machine import format_size

    sizes = [len(getattr(frame, "ids", ())) for frame in frames]
    if not sizes:
        return
    largest = max(sizes)
    cap = getattr(detector, "max_frame_bytes", None)
    if isinstance(cap, numbers.Real) and not isinstance(cap, bool) and 0 < cap < limit:
        limit, hint = int(cap), ""
        limit_text = f"the {format_size(cap)} {name} allows one frame, whatever the memory given"
    needed = frame_memory(detector, largest)
    if needed is None or needed <= limit:
        return
    low, high = 0, largest  # the most people that fit: frame_memory(low) fits, (high) does not
    while high - low > 1:
        middle = (low + high) // 2
        fits = (frame_memory(detector, middle) or 0) <= limit
        low, high = (middle, high) if fits else (low, middle)
    index = sizes.index(largest)
    of = f" of {source}" if source else ""
    raise FrameTooLarge(
        f"{name}: {_frame_text(index, frames[index])}{of} holds {largest:,} people, which would "
        f"take about {format_size(needed)} to predict, more than {limit_text}: at most "
        f"{low:,} people a frame fit" + (f"; {hint}" if hint else "")
    )


def _frame_text(index: int, frame: Any) -> str:
    sequence = getattr(frame, "sequence", "")
    time = getattr(frame, "time", None)
    when = f"t={time:g} s" if isinstance(time, (int, float)) else ""
    inside = " ".join(part for part in (sequence, when) if part)
    return f"frame {index} ({inside})" if inside else f"frame {index}"


def check_predictions(name: str, frames: Sequence[Frame], partitions: Any) -> list[Sequence[Group]]:
    """Checks that ``partitions`` holds one partition of each frame's people, in order.

    Args:
        name: the detector's name, for the message.
        frames: the frames it was given.
        partitions: what its ``predict`` returned.

    Returns:
        The partitions, as a list (the groups as the detector gave them).

    Raises:
        DetectorError: naming the detector and the frame (its index in ``frames``, sequence and
            time): not a sequence, the wrong number of partitions, or a partition naming
            someone not in the frame, someone twice, someone in no group, a non-integer id or
            an empty group.
    """
    from reform.metrics import check_partition  # numpy: not needed to list the catalogue

    frames = list(frames)
    if isinstance(partitions, (str, bytes, Mapping)) or not isinstance(partitions, Iterable):
        raise DetectorError(
            f"{name}: detector returned {_describe(partitions)}, expected one partition per "
            f"frame ({len(frames)} frames)"
        )
    partitions = list(partitions)
    if len(partitions) != len(frames):
        raise DetectorError(
            f"{name}: detector returned {len(partitions)} partitions for {len(frames)} frames"
        )
    for index, (frame, partition) in enumerate(zip(frames, partitions, strict=True)):
        try:
            check_partition(
                partition, frame, where=f"{name}: detector output for {_frame_text(index, frame)}"
            )
        except ValueError as exc:
            raise DetectorError(str(exc)) from None
    return partitions


def _culprit(
    predict: Callable[..., Any], frames: Sequence[Frame]
) -> tuple[str, BaseException | None]:
    """The first frame that makes ``predict`` raise on its own, and what it raised; ``("", None)``
    when none does (the detector fails on the batch only)."""
    if len(frames) == 1:
        return _frame_text(0, frames[0]), None
    for index, frame in enumerate(frames):
        try:
            _read_lazy(predict([frame]))
        except _RAISED as exc:  # looking for the frame, whatever it raises
            return _frame_text(index, frame), exc
    return "", None


# What a detector may raise that is reported as its failure: any exception, and SystemExit (a
# sys.exit() in someone's predict must not end the command without a word). Not
# KeyboardInterrupt: Ctrl-C stops the run.
_RAISED = (Exception, SystemExit)


def _read_lazy(returned: Any) -> Any:
    """What ``predict`` returned, with its lazy parts read (a generator of partitions, a
    partition that is an iterator), so that what they raise is raised inside the detector."""
    if isinstance(returned, Iterator):
        returned = list(returned)
    if isinstance(returned, (list, tuple)):
        returned = [list(p) if isinstance(p, Iterator) else p for p in returned]
    return returned


def _without_truth(frames: Sequence[Frame]) -> list[Frame]:
    """The frames as a detector may see them: their ground truth taken away."""
    return [f if f.groups is None else f.replace(groups=None, listed_groups=None) for f in frames]


def predict_deadline(frames: Sequence[Frame], per_frame_s: float | None = None) -> float:
    """Seconds a detector may take to predict ``frames``: ``per_frame_s`` for each frame, by
    default :data:`PREDICT_TIMEOUT_S` plus :data:`PREDICT_TIMEOUT_S_PER_PAIR` for each pair of
    people in it (a frame of 20 people: 14.5 s)."""
    if per_frame_s is not None:
        return per_frame_s * max(1, len(frames))
    sizes = [len(getattr(f, "ids", ())) for f in frames]
    pairs = sum(n * (n - 1) // 2 for n in sizes)
    return PREDICT_TIMEOUT_S * max(1, len(frames)) + PREDICT_TIMEOUT_S_PER_PAIR * pairs


def _held(stack: Sequence[Any], frames: Sequence[Frame]) -> int | None:
    """The index in ``frames`` of the frame that the innermost Python frame of ``stack``
    holding one of them has as a local variable (what a detector was working on), or None."""
    index = {id(frame): k for k, frame in enumerate(frames)}
    for python_frame in stack:
        try:
            values = list(python_frame.f_locals.values())
        except Exception:  # noqa: BLE001 - a frame that cannot show its locals says nothing
            continue
        for value in values:
            if id(value) in index:
                return index[id(value)]
    return None


def run_detector(
    name: str,
    detector: Any,
    frames: Sequence[Frame],
    *,
    oracle: bool = False,
    deadline_s: float | None = None,
    source: str = "",
) -> list[Sequence[Group]]:
    """``detector.predict(frames)``, checked by :func:`check_predictions`.

    The detector sees the frames without their ground truth (``groups`` is None), so that no
    detector can score by reading the answer. An exception raised inside the detector (or a
    ``sys.exit``; lazy output is read first) becomes one line naming the detector, the
    exception's type and message, and the first frame that raises on its own (found by
    predicting the frames one at a time again, only after a failure).

    Args:
        name: the detector's name, for messages.
        detector: an object with ``predict`` (:class:`Detector`).
        frames: the frames to partition.
        oracle: hand the frames over with their ground truth: only for a detector that reads
            it on purpose, as an upper bound (the gymnasium environment's ``"truth"``).
        deadline_s: seconds ``predict`` may take for each frame (the batch gets as many times
            this as it has frames); default :func:`predict_deadline`'s, scaled by the people in
            each frame. At the deadline ``predict`` is stopped (`reform.deadline.within`).
        source: where the frames come from (a file, a dataset), for messages.

    Returns:
        One partition per frame, as a list.

    Raises:
        DetectorError: the detector has no callable ``predict``, raised, returned something
            that is not one partition per frame, or did not return by the deadline (naming the
            frame it was working on, where a local variable of its code holds one).
    """
    predict = getattr(detector, "predict", None)
    if not callable(predict):
        raise DetectorError(f"{name}: {_describe(detector)} has no callable predict(frames)")
    frames = list(frames)
    unlabelled = frames if oracle else _without_truth(frames)
    seconds = predict_deadline(frames, deadline_s)
    of = f" of {source}" if source else ""
    stuck = _stuck(f"{name}: predict on {len(frames)} frame(s){of}", seconds)
    try:
        partitions = within(seconds, lambda: _read_lazy(predict(unlabelled)), stuck=stuck)
    except DeadlineExpired as exc:
        held = _held(exc.stack, unlabelled)
        where = "the batch" if held is None else _frame_text(held, frames[held])
        batch = f", {len(frames)} frames in one call" if len(frames) > 1 else ""
        raise DetectorError(
            f"{name}: the detector did not finish within {exc.seconds:g} s (predict on "
            f"{where}{of}{batch}); {_TIMEOUT_HINT}"
        ) from None
    except _RAISED as exc:  # the detector is someone's code: report it in one line
        where, alone = _culprit(predict, unlabelled)
        where = where or f"a batch of {len(frames)} frames (no frame alone)"
        raised = alone or exc
        message = " ".join(str(raised).split())
        raise DetectorError(
            f"{name}: detector raised {type(raised).__name__} on {where}"
            + (f": {message}" if message else "")
        ) from exc
    return check_predictions(name, frames, partitions)


def fit_detector(name: str, detector: Any, frames: Sequence[Frame]) -> Any:
    """A copy of ``detector`` fitted on ``frames`` when it has ``fit``, else ``detector`` itself.

    The detector passed in is left as it was (it is copied with `copy.deepcopy` first).

    Raises:
        DetectorError: one line naming the detector when its ``fit`` raises or is not callable.
    """
    fit = getattr(detector, "fit", None)
    if fit is None:
        return detector
    if not callable(fit):
        raise DetectorError(f"{name}: the detector's fit is {_describe(fit)}, not a method")
    try:
        fitted = copy.deepcopy(detector)
    except Exception as exc:  # noqa: BLE001 - a lock, a socket, an open file...
        raise DetectorError(
            f"{name}: the detector cannot be copied to be fitted (copy.deepcopy raised "
            f"{_one_line(exc)}): keep what cannot be copied out of its attributes"
        ) from exc
    try:
        fitted.fit(frames)
    except _RAISED as exc:  # the detector is someone's code: report it in one line
        raise DetectorError(
            f"{name}: detector's fit raised {_one_line(exc)} (on {len(frames)} frames)"
        ) from exc
    return fitted


# The built-in catalogue (reform.catalogue) registers itself on import: one table of every
# detector the project ships, each with its options declared once.
import reform.catalogue  # noqa: E402, F401


def prepare_detector(
    name: str,
    detector: Any,
    *,
    dataset: Any = None,
    training: Sequence[Frame] | None = None,
) -> Any:
    """The detector ready to predict on ``dataset``: specialised to it when it has
    ``for_dataset`` (``needs="dataset"``), fitted on ``training`` when it must learn first.

    Args:
        name: the detector's name, for messages.
        detector: what `make_detector` made.
        dataset: the `reform.Dataset` it will run on, or None.
        training: annotated frames to fit on (never the frames that are scored), or None.

    Returns:
        The detector to run (a new object when specialised or fitted; ``detector`` is left as it
        was).

    Raises:
        DetectorError: one line: the detector needs a dataset or training frames that were not
            given, or does not apply to the dataset (naming why).
    """
    for_dataset = getattr(detector, "for_dataset", None)
    if callable(for_dataset):
        if dataset is None:
            raise DetectorError(f"{name}: runs on a dataset's own settings; none was given")
        try:
            detector = for_dataset(dataset)
        except _RAISED as exc:
            raise DetectorError(f"{name}: {' '.join(str(exc).split())}") from exc
    info = _REGISTRY.get(name)
    if info is not None and info.needs == "training":
        if not training:
            raise DetectorError(
                f"{name}: learns its settings from annotated training frames; none were given"
            )
        detector = fit_detector(name, detector, training)
    return detector
