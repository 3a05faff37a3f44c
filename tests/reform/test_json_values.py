import json
import math
from dataclasses import dataclass

import pytest

from reform.bootstrap import Interval
from reform.json_values import json_record


@dataclass(frozen=True)
class _Result:
    name: str
    pvalue: float
    sizes: tuple[int, ...]
    interval: Interval
    by_key: dict


def test_json_record_keeps_field_order_and_converts_values() -> None:
    result = _Result(
        "a", math.nan, (2, 3), Interval(0.5, 0.25, math.inf), {"x": 1.5, "y": math.nan}
    )
    out = json_record(result, {"pvalue": "p"}, name="b")
    assert list(out) == ["name", "p", "sizes", "interval", "by_key"]
    assert out == {
        "name": "b",
        "p": None,
        "sizes": [2, 3],
        "interval": {"value": 0.5, "low": 0.25, "high": None},
        "by_key": {"x": 1.5, "y": None},
    }
    json.dumps(out, allow_nan=False)


def test_json_record_refuses_an_unknown_field() -> None:
    result = _Result("a", 0.1, (), Interval(0.5, 0.25, 0.75), {})
    with pytest.raises(TypeError, match="_Result has no field colour"):
        json_record(result, colour="red")
    with pytest.raises(TypeError, match="_Result has no field p"):
        json_record(result, {"p": "pvalue"})
