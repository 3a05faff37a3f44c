"""Crowd options of ``mingle``: closer bodies, uneven groups; measured on real MuJoCo episodes."""

from __future__ import annotations

import numpy as np
import pytest

import scenarios
from reform.calibration import characterise_dataset
from sim.episode import scene_spec, simulate_episode
from sim.experiments.crowd_shapes import nearest_neighbour
from sim.scene import PersonSpec

PARTY = {"people": 16, "duration": 150.0}


def _frames(seed: int, **options):
    episode = simulate_episode("mingle", seed=seed, rate=0.5, options={**PARTY, **options})
    return list(episode.dataset)


@pytest.fixture(scope="module")
def close():
    return [f for seed in (0, 1) for f in _frames(seed, spacing=0.46)]


def test_default_bodies_keep_about_0_6_m_apart():
    nn = nearest_neighbour(_frames(0))
    assert np.quantile(nn, 0.1) > 0.58


def test_spacing_lets_people_stand_shoulder_to_shoulder(close):
    nn = nearest_neighbour(close)
    assert np.quantile(nn, 0.1) < 0.5
    # the motion keeps the bodies' discs apart: radius (0.46 - 0.03) / 2 each, plus sway room
    assert nn.min() >= 0.46 - 0.03 - 1e-6
    made = scenarios.make("mingle", seed=0, **PARTY, spacing=0.46)
    assert [p.radius for p in scene_spec(made.stage).people] == pytest.approx([0.215] * 16)
    default = scenarios.make("mingle", seed=0, **PARTY)
    assert {p.radius for p in default.stage.people} == {None}


def _symmetry_per_member(**options) -> float:
    """Mean Symmetry over a member (degrees) of the groups of 3 or more of six fresh parties
    (seconds 0-30 of seeds 0-5: every group is drawn anew)."""
    frames = [
        f
        for seed in range(6)
        for f in simulate_episode(
            "mingle", seed=seed, rate=0.5, options={"people": 18, "duration": 30.0, **options}
        ).dataset
    ]
    shapes = characterise_dataset(frames).shapes
    big = shapes.size >= 3
    return float((shapes.symmetry[big] / shapes.size[big]).mean())


def test_unevenness_raises_symmetry_into_salsas_range():
    # SALSA's training split: 21-26 degrees per member for sizes 3-7 (64, 89, 129, 128, 158)
    even = _symmetry_per_member(spacing=0.46)
    uneven = _symmetry_per_member(spacing=0.46, unevenness=1.0)
    assert even < 19.0
    assert 21.0 < uneven < 32.0


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"spacing": 0.3}, r"^mingle: option spacing must be within \[0.43, 1\] m, got 0.3$"),
        ({"unevenness": 1.5}, r"^mingle: option unevenness must be within \[0, 1\], got 1.5$"),
    ],
)
def test_bad_crowd_options_give_one_line(options, message):
    with pytest.raises(ValueError, match=message):
        scenarios.make("mingle", seed=0, **options)


def test_a_body_radius_out_of_range_is_refused():
    with pytest.raises(ValueError, match=r"person 3: body_radius must be within \[0.15, 0.5\] m"):
        PersonSpec(id=3, position=(0.0, 0.0), body_radius=0.1)
