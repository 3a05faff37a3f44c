"""The estimator base of the detectors that learn nothing with scikit-learn keeps scikit-learn's
contract: every catalogued detector on it answers ``get_params``, ``set_params``, ``clone`` and
``repr`` as a scikit-learn estimator with the same ``__init__`` does."""

from __future__ import annotations

import pytest
from sklearn.base import BaseEstimator, clone
from sklearn.exceptions import NotFittedError
from sklearn.utils.validation import check_is_fitted
from toy_scenes import toy_frames

from reform import make_detector
from reform.detectors import builtin_names
from reform.estimator import Estimator, not_fitted_error


def _light(name: str) -> Estimator | None:
    """The catalogue's ``name``, or None for a detector that learns with scikit-learn (which
    keeps scikit-learn's own base)."""
    detector = make_detector(name)
    if isinstance(detector, Estimator):
        return detector
    assert isinstance(detector, BaseEstimator), type(detector).__mro__
    return None


def _twin(detector: Estimator) -> BaseEstimator:
    """A scikit-learn estimator of the same class name and ``__init__``, the same parameters."""
    cls = type(detector)
    twin = type(cls.__name__, (BaseEstimator,), {"__init__": cls.__init__})
    return twin(**detector.get_params(deep=False))


def _changed(detector: Estimator) -> Estimator:
    """``detector`` with every parameter that is not an estimator given a value of its own, long
    enough that the repr wraps."""
    params = detector.get_params(deep=False)
    values = {
        key: round(0.123456789 * (k + 1), 9) if not hasattr(value, "get_params") else value
        for k, (key, value) in enumerate(params.items())
    }
    return clone(detector).set_params(**values)


@pytest.mark.parametrize("name", builtin_names())
def test_params_clone_and_repr_are_scikit_learns(name: str) -> None:
    detector = _light(name)
    if detector is None:
        return
    for made in (detector, _changed(detector)):
        twin = _twin(made)
        assert made.get_params(deep=True) == twin.get_params(deep=True)
        assert made.get_params(deep=False) == twin.get_params(deep=False)
        assert repr(made) == repr(twin)
        copy = clone(made)
        assert type(copy) is type(made) and copy is not made
        assert repr(copy.get_params()) == repr(made.get_params())


@pytest.mark.parametrize("name", builtin_names())
def test_set_params_is_scikit_learns(name: str) -> None:
    detector = _light(name)
    if detector is None:
        return
    twin = _twin(detector)
    params = detector.get_params(deep=True)
    assert detector.set_params(**params) is detector
    assert detector.get_params(deep=True) == twin.set_params(**params).get_params(deep=True)
    messages = []
    for made in (detector, twin):
        with pytest.raises(ValueError) as error:
            made.set_params(no_such_parameter=1)
        messages.append(str(error.value))
    assert messages[0] == messages[1]
    assert "Invalid parameter 'no_such_parameter' for estimator" in messages[0]


def test_nested_parameters_are_set_through_the_outer_estimator() -> None:
    outer = make_detector("smoothed", detector="gcff", window=3.0)
    assert outer.get_params()["detector__stride"] == 0.7
    copy = clone(outer).set_params(detector__stride=0.5, window=1.0)
    assert (copy.detector.stride, copy.window) == (0.5, 1.0)
    assert outer.detector.stride == 0.7 and copy.detector is not outer.detector
    assert repr(copy) == "SlidingMajority(detector=Gcff(mdl=3.0, stride=0.5), window=1.0)"


def test_clone_leaves_what_was_learned_behind() -> None:
    tuned = make_detector("gcff-tuned").fit(toy_frames(0, 10))
    assert hasattr(tuned, "stride_")
    check_is_fitted(tuned)
    fresh = clone(tuned)
    assert not hasattr(fresh, "stride_")
    with pytest.raises(NotFittedError, match="Gcff instance is not fitted yet"):
        check_is_fitted(fresh)
    with pytest.raises(NotFittedError, match="must be fitted on training frames"):
        fresh.predict(toy_frames(0, 1))


def test_a_long_repr_is_wrapped_and_elided_as_scikit_learns() -> None:
    names = [f"parameter_{k:02d}" for k in range(40)]
    init = f"def __init__(self, *, {', '.join(f'{n}=0.0' for n in names)}):\n"
    init += "".join(f"    self.{n} = {n}\n" for n in names)
    space: dict = {}
    exec(init, space)  # noqa: S102 (a signature of 40 parameters, written out)
    Wide = type("Wide", (Estimator,), {"__init__": space["__init__"]})
    for n in (3, 40):
        wide = Wide(**{name: 1 / 7 for name in names[:n]})
        text = repr(wide)
        assert text == repr(_twin(wide))
    assert "\n" in text and "..." in text and len("".join(text.split())) < 800


def test_varargs_in_init_are_refused_as_scikit_learn_refuses_them() -> None:
    class Loose(Estimator):
        def __init__(self, *sizes: int) -> None:
            self.sizes = sizes

    with pytest.raises(RuntimeError, match=r"no varargs"):
        Loose(1, 2).get_params()


def test_not_fitted_error_is_scikit_learns() -> None:
    error = not_fitted_error("call fit first")
    assert isinstance(error, NotFittedError) and isinstance(error, ValueError)
    assert str(error) == "call fit first"
