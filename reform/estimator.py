"""The estimator base of the detectors that learn nothing with scikit-learn.

scikit-learn's ``BaseEstimator`` costs a command close to a second of CPU to import (with
``sklearn.base`` come scipy.stats, pandas, pyarrow and narwhals), which ``evaluate --detector
gcff`` would pay for a detector that never calls scikit-learn. :class:`Estimator` gives those
detectors scikit-learn's estimator contract with the standard library only:

* ``get_params(deep=True)`` and ``set_params(**params)`` read the parameters from the
  ``__init__`` signature, nested ``<parameter>__<name>`` included, with scikit-learn's errors;
* ``sklearn.base.clone`` works (it needs ``get_params`` only), and so do
  ``sklearn.utils.validation.check_is_fitted`` (``__sklearn_tags__``, read when scikit-learn asks
  for it, so scikit-learn is loaded by then) and scikit-learn's parameter searches;
* ``repr`` is scikit-learn's: the class and the parameters that differ from their defaults, by
  name, lines wrapped at 80 columns under the opening parenthesis, long ones elided.

What scikit-learn's base has beyond that (the HTML display in notebooks, metadata routing,
``set_output``, the ``print_changed_only`` setting) is not needed by a detector; a detector that
learns with scikit-learn (REFORM, DANTE) keeps scikit-learn's base, and with it all of that.
``tests/reform/test_estimator.py`` holds every catalogued detector's parameters, ``clone`` and
``repr`` equal to those of a scikit-learn estimator with the same ``__init__``.
"""

from __future__ import annotations

import inspect
import math
import re
import sys
from collections import defaultdict
from typing import Any

__all__ = ["Estimator", "not_fitted_error"]

_WIDTH = 80  # columns of scikit-learn's repr
_MAX_ITEMS = 30  # parameters shown before "..."
_MAX_NONBLANK = 700  # non-blank characters of a repr before its middle is elided


class Estimator:
    """Base of an estimator whose ``__init__`` only stores its keyword parameters.

    Subclasses declare every parameter in the signature of ``__init__`` (no ``*args``) and store
    each under its own name, as scikit-learn requires; learned attributes end in ``_``.
    """

    @classmethod
    def _get_param_names(cls) -> list[str]:
        """The parameters of ``__init__``, sorted by name."""
        init = cls.__init__
        if init is object.__init__:
            return []
        signature = inspect.signature(init)
        parameters = [
            p for p in signature.parameters.values() if p.name != "self" and p.kind != p.VAR_KEYWORD
        ]
        for p in parameters:
            if p.kind == p.VAR_POSITIONAL:
                raise RuntimeError(
                    "scikit-learn estimators should always specify their parameters in the "
                    f"signature of their __init__ (no varargs). {cls} with constructor "
                    f"{signature} doesn't  follow this convention."
                )
        return sorted(p.name for p in parameters)

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """The estimator's parameters by name; with ``deep``, those of parameters that are
        estimators too, as ``<parameter>__<name>``."""
        out: dict[str, Any] = {}
        for key in self._get_param_names():
            value = getattr(self, key)
            if deep and hasattr(value, "get_params") and not isinstance(value, type):
                out.update((f"{key}__{k}", v) for k, v in value.get_params().items())
            out[key] = value
        return out

    def set_params(self, **params: Any) -> Estimator:
        """Sets parameters by name (``<parameter>__<name>`` for a nested estimator's); returns
        ``self``.

        Raises:
            ValueError: a name that is not a parameter of the estimator.
        """
        if not params:
            return self
        valid = self.get_params(deep=True)
        nested: defaultdict[str, dict[str, Any]] = defaultdict(dict)
        for key, value in params.items():
            key, delim, sub_key = key.partition("__")
            if key not in valid:
                raise ValueError(
                    f"Invalid parameter {key!r} for estimator {self}. "
                    f"Valid parameters are: {self._get_param_names()!r}."
                )
            if delim:
                nested[key][sub_key] = value
            else:
                setattr(self, key, value)
                valid[key] = value
        for key, sub_params in nested.items():
            valid[key].set_params(**sub_params)
        return self

    def __sklearn_tags__(self) -> Any:
        """scikit-learn's tags of an estimator of no particular kind (scikit-learn asks for them,
        so it is loaded by then)."""
        from sklearn.utils import Tags, TargetTags  # noqa: PLC0415 (only scikit-learn calls this)

        return Tags(
            estimator_type=None,
            target_tags=TargetTags(required=False),
            transformer_tags=None,
            regressor_tags=None,
            classifier_tags=None,
        )

    def __repr__(self) -> str:
        text = _format(self, indent=0, allowance=0)
        return _elide(text) if len("".join(text.split())) > _MAX_NONBLANK else text


def not_fitted_error(message: str) -> Exception:
    """scikit-learn's ``NotFittedError`` (a ``ValueError`` and an ``AttributeError``) with
    ``message``: imported only when an estimator is used before it is fitted."""
    from sklearn.exceptions import NotFittedError  # noqa: PLC0415 (the error path only)

    return NotFittedError(message)


def _changed_params(estimator: Any) -> dict[str, Any]:
    """The parameters given values other than their defaults (compared by ``repr``)."""
    defaults = {
        name: p.default for name, p in inspect.signature(estimator.__init__).parameters.items()
    }

    def changed(name: str, value: Any) -> bool:
        if name not in defaults or defaults[name] is inspect.Parameter.empty:
            return True
        default = defaults[name]
        if _is_estimator(value) and value.__class__ != default.__class__:
            return True
        return repr(value) != repr(default) and not (_is_nan(default) and _is_nan(value))

    return {k: v for k, v in estimator.get_params(deep=False).items() if changed(k, v)}


def _is_nan(value: Any) -> bool:
    return isinstance(value, float) and math.isnan(value)


def _is_estimator(value: Any) -> bool:
    """Whether ``value`` is printed as an estimator: one of ours, or scikit-learn's (then
    scikit-learn is loaded)."""
    if isinstance(value, Estimator):
        return True
    base = sys.modules.get("sklearn.base")
    return base is not None and isinstance(value, base.BaseEstimator)


def _one_line(value: Any) -> str:
    """``value`` on one line, as scikit-learn's printer first tries it."""
    if _is_estimator(value):
        params = sorted(_changed_params(value).items())
        inner = ", ".join(f"{k}={_one_line(v)}" for k, v in params)
        return f"{type(value).__name__}({inner})"
    return repr(value)


def _format(value: Any, *, indent: int, allowance: int) -> str:
    """``value`` printed from column ``indent``, keeping ``allowance`` columns free at the end
    of its last line (scikit-learn's compact printer, indented at the class name)."""
    line = _one_line(value)
    if len(line) <= _WIDTH - indent - allowance or not _is_estimator(value):
        return line
    name = type(value).__name__
    items = sorted(_changed_params(value).items())
    indent += len(name) + 1
    allowance += 1  # the closing parenthesis
    newline = ",\n" + " " * indent
    out = [f"{name}("]
    width = max_width = _WIDTH - indent + 1
    delim = ""
    for n, (key, item) in enumerate(items):
        if n == _MAX_ITEMS:
            out.append(", ...")
            break
        last = n == len(items) - 1
        if last:
            width -= allowance
            max_width -= allowance
        text = f"{key}={_one_line(item)}"
        w = len(text) + 2
        if width < w:
            width = max_width
            if delim:
                delim = newline
        if width >= w:
            width -= w
            out += [delim, text]
            delim = ", "
            continue
        out += [
            delim,
            f"{key}=",
            _format(item, indent=indent + len(key) + 1, allowance=allowance if last else 1),
        ]
        delim = newline
    out.append(")")
    return "".join(out)


def _elide(text: str) -> str:
    """``text`` with its middle replaced by "...", keeping about half of ``_MAX_NONBLANK``
    non-blank characters at each end."""
    pattern = rf"^(\s*\S){{{_MAX_NONBLANK // 2}}}"
    left = re.match(pattern, text).end()  # type: ignore[union-attr]
    right = re.match(pattern, text[::-1]).end()  # type: ignore[union-attr]
    if "\n" in text[left:-right]:
        right = re.match(pattern + r"[^\n]*\n", text[::-1]).end()  # type: ignore[union-attr]
    if left + 3 < len(text) - right:
        return text[:left] + "..." + text[-right:]
    return text
