"""Annotation models (reform.annotation): each step on hand-made frames, the order of the steps,
seeded draws, and every bad setting refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from reform import Frame
from reform.annotation import (
    ANNOTATION_RANGES,
    MAX_SCALE_SD,
    AnnotationModel,
    draw_annotation,
    parse_annotation,
)


def frame(t: float, groups=((1, 2),), *, yaw=(0.3, -2.0, 1.6), head_yaw=(0.9, np.nan, -0.2)):
    return Frame(
        ids=np.array([1, 2, 3]),
        position=np.array([[1.0, 2.0], [1.5, 2.0], [-4.0, 0.5]]),
        yaw=np.array(yaw),
        head_position=np.array([[1.0, 2.1], [np.nan, np.nan], [-4.0, 0.6]]),
        head_yaw=np.array(head_yaw),
        groups=groups,
        time=t,
        sequence="s",
    )


def episode(n: int = 6, groups=((1, 2),)):
    return [frame(0.5 * (k + 1), groups) for k in range(n)]


def test_the_identity_leaves_frames_as_they_are():
    frames = episode()
    assert AnnotationModel().identity
    assert AnnotationModel().apply(frames, np.random.default_rng(0)) == tuple(frames)


def test_head_orientation_where_the_head_is_seen():
    (out,) = AnnotationModel(orientation="head").apply([frame(1.0)], np.random.default_rng(0))
    np.testing.assert_array_equal(out.yaw, [0.9, -2.0, -0.2])  # person 2 has no head: body kept
    np.testing.assert_array_equal(out.position, frame(1.0).position)


def test_orientations_coded_in_k_directions():
    (out,) = AnnotationModel(directions=4).apply([frame(1.0)], np.random.default_rng(0))
    # hand-computed: 0.3 -> 0, -2.0 -> -pi/2, 1.6 -> pi/2; heads 0.9 -> pi/2, NaN stays, -0.2 -> 0
    np.testing.assert_allclose(out.yaw, [0.0, -math.pi / 2, math.pi / 2])
    np.testing.assert_allclose(out.head_yaw, [math.pi / 2, np.nan, 0.0])
    (half,) = AnnotationModel(directions=2).apply(
        [frame(1.0, yaw=(3.0, -3.0, 1.0))], np.random.default_rng(0)
    )
    np.testing.assert_allclose(half.yaw, [-math.pi, -math.pi, 0.0])  # pi wraps to -pi
    (one,) = AnnotationModel(directions=1).apply([frame(1.0)], np.random.default_rng(0))
    np.testing.assert_allclose(one.yaw, 0.0)


def test_one_scale_error_per_episode():
    frames = episode()
    out = AnnotationModel(scale_sd=0.1).apply(frames, np.random.default_rng(4))
    factor = 1.0 + 0.1 * np.random.default_rng(4).normal()
    for before, after in zip(frames, out, strict=True):
        np.testing.assert_allclose(after.position, before.position * factor)
        np.testing.assert_allclose(after.head_position, before.head_position * factor)
        np.testing.assert_array_equal(after.yaw, before.yaw)
    widest = AnnotationModel(scale_sd=MAX_SCALE_SD)  # an error of 100 %: kept above 0.5
    factors = [
        widest.apply(frames[:1], np.random.default_rng(seed))[0].position[0, 0]
        / frames[0].position[0, 0]
        for seed in range(20)
    ]
    assert min(factors) == pytest.approx(0.5) and max(factors) > 1.5
    with pytest.raises(ValueError, match=r"annotation scale_sd must be at most 1, got 1.5"):
        AnnotationModel(scale_sd=1.5)


def test_tracker_errors_then_coding():
    model = AnnotationModel(position_noise=0.05, yaw_noise=0.2, dropout=0.3, directions=8)
    out = model.apply(episode(40), np.random.default_rng(3))
    assert sum(f.n_people for f in out) < 40 * 3  # people missed
    step = 2 * math.pi / 8
    for f in out:
        np.testing.assert_allclose(np.round(f.yaw / step) * step, f.yaw)  # coded after jitter
        assert all(set(g) <= set(f.ids.tolist()) for g in f.groups)
    again = model.apply(episode(40), np.random.default_rng(3))
    assert again == out


def test_the_annotator_calls_a_group_only_once_it_has_lasted():
    short = [frame(0.5 * k, ((1, 2),) if 2 <= k <= 4 else ()) for k in range(10)]  # 1 s
    long = [frame(0.5 * k, ((1, 2),) if 2 <= k <= 8 else ()) for k in range(10)]  # 3 s
    model = AnnotationModel(min_group_seconds=2.0)
    assert all(f.groups in ((), ((1,), (2,))) for f in model.apply(short, None))
    kept = model.apply(long, None)
    assert [f.groups for f in kept] == [f.groups for f in long]


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"directions": 0}, r"directions must be a whole number >= 1 \(or continuous\), got 0"),
        ({"directions": -4}, r"directions must be a whole number >= 1 .*got -4"),
        ({"directions": 2.5}, r"directions must be a whole number >= 1 .*got 2.5"),
        ({"directions": True}, r"directions must be a whole number >= 1 .*got True"),
        ({"directions": 3601}, r"directions must be at most 3600 \(finer is continuous"),
        ({"yaw_noise": 7.0}, r"annotation yaw_noise must be at most 6.28319, got 7.0"),
        ({"scale_sd": -0.01}, r"annotation scale_sd must be a finite number >= 0, got -0.01"),
        (
            {"position_noise": math.nan},
            r"annotation position_noise must be a finite number >= 0, got nan",
        ),
        ({"yaw_noise": "a"}, r"annotation yaw_noise must be a number, got 'a'"),
        ({"dropout": 1.5}, r"annotation dropout must be in \[0, 1\], got 1.5"),
        (
            {"min_group_seconds": -1},
            r"annotation min_group_seconds must be a finite number >= 0, got -1.0",
        ),
        ({"orientation": "feet"}, r"orientation must be one of \['body', 'head'\], got 'feet'"),
    ],
    ids=lambda value: str(value)[:24],
)
def test_settings_outside_their_meaning_are_refused(settings, message):
    with pytest.raises(ValueError, match=message):
        AnnotationModel(**settings)


def test_settings_from_the_command_line():
    assert parse_annotation(["directions=24", "orientation=head", "dropout=0.02"]) == (
        AnnotationModel(orientation="head", directions=24, dropout=0.02)
    )
    assert parse_annotation(["directions=continuous"]) == AnnotationModel()
    with pytest.raises(ValueError, match=r"annotation setting 'size=3': expected KEY=VALUE"):
        parse_annotation(["size=3"])
    with pytest.raises(ValueError, match=r"annotation scale_sd must be a number, got 'big'"):
        parse_annotation(["scale_sd=big"])
    with pytest.raises(ValueError, match=r"directions must be a whole number >= 1"):
        parse_annotation(["directions=0"])


def test_randomised_models_span_the_documented_ranges():
    rng = np.random.default_rng(0)
    models = [draw_annotation(rng) for _ in range(200)]
    assert {m.directions for m in models} == set(ANNOTATION_RANGES["directions"])
    assert {m.orientation for m in models} == {"body", "head"}
    for name in ("scale_sd", "position_noise", "yaw_noise", "dropout", "min_group_seconds"):
        low, high = ANNOTATION_RANGES[name]
        values = [getattr(m, name) for m in models]
        assert low <= min(values) and max(values) <= high and max(values) - min(values) > 0
    assert draw_annotation(np.random.default_rng(5)) == draw_annotation(np.random.default_rng(5))
