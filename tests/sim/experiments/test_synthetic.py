"""Synthetic training data: sources, balance, tracker-noise calibration, realism measures."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from reform.perturb import Perturbation
from sim.episode import simulate_episode
from sim.experiments.synthetic import (
    SyntheticSource,
    balance_pairs,
    calibrate_tracker_noise,
    count_pairs,
    generate_sources,
)


@pytest.fixture(scope="module")
def party():
    """Two minutes of mingle, one frame every 2 s."""
    return simulate_episode("mingle", seed=5, duration=120.0, rate=0.5).dataset.annotated()


@pytest.fixture(scope="module")
def game():
    return simulate_episode("word-improv", seed=5, duration=200.0, rate=0.5).dataset.annotated()


def test_source_folder_names_its_data() -> None:
    a = SyntheticSource("mingle", episodes=3)
    assert a.folder(0) == SyntheticSource("mingle", episodes=9).folder(0)  # more episodes extend
    assert a.folder(0).startswith("mingle-seed0-")
    assert a.folder(1) != a.folder(0)
    assert SyntheticSource("mingle", episodes=3, options={"people": 12}).folder(0) != a.folder(0)
    assert SyntheticSource("mingle", episodes=3, rate=1.0).folder(0) != a.folder(0)
    with pytest.raises(ValueError, match="episodes must be an int >= 1, got 0"):
        SyntheticSource("mingle", episodes=0)


def test_count_pairs(party) -> None:
    # Hand count: n (n - 1) / 2 per frame.
    assert count_pairs(party) == sum(f.n_people * (f.n_people - 1) // 2 for f in party)
    assert count_pairs(()) == 0


def test_balance_pairs_evens_out_the_sources(party, game) -> None:
    kept = balance_pairs({"mingle": party, "word-improv": game})
    small = min(count_pairs(party), count_pairs(game))
    assert list(kept) == ["mingle", "word-improv"]
    for name, frames in kept.items():
        # Within one frame's worth of pairs of the smallest source.
        most = max(f.n_people * (f.n_people - 1) // 2 for f in frames)
        assert abs(count_pairs(frames) - small) <= most, name
    larger = "mingle" if count_pairs(party) > count_pairs(game) else "word-improv"
    source = party if larger == "mingle" else game
    times = [f.time for f in kept[larger]]
    assert times == sorted(times)  # an even subset, in order
    assert times[0] == source[0].time and times[-1] == source[-1].time  # spans the episode
    assert balance_pairs({"mingle": party, "word-improv": game}) == kept
    with pytest.raises(ValueError, match="every source needs frames with pairs"):
        balance_pairs({"mingle": party, "empty": ()})


def test_calibration_recovers_known_noise(party) -> None:
    """A reference made by perturbing the frames with known noise is matched best by that
    noise (other draws, so not the same numbers)."""
    reference = Perturbation(position_noise=0.1, yaw_noise=0.4).apply_all(
        party, np.random.default_rng(99)
    )
    calibration = calibrate_tracker_noise(
        party, reference, seed=0, position_grid=(0.0, 0.1, 0.3), yaw_grid=(0.0, 0.4, 1.0)
    )
    assert (calibration.position_noise, calibration.yaw_noise) == (0.1, 0.4)
    assert len(calibration.grid) == 9
    ks, total = calibration.ks_at(0.1, 0.4)
    assert len(ks) == 4 and total == pytest.approx(calibration.objective)
    assert all(total <= sum(k) for _, _, k in calibration.grid)
    assert calibration.perturbation() == Perturbation(position_noise=0.1, yaw_noise=0.4)
    data = calibration.to_json()
    assert data["position_noise_m"] == 0.1 and len(data["grid"]) == 9
    with pytest.raises(ValueError, match="not on the calibration grid"):
        calibration.ks_at(0.2, 0.4)
    with pytest.raises(ValueError, match="calibration needs synthetic and reference frames"):
        calibrate_tracker_noise((), reference, seed=0)


def test_generate_sources_refuses_a_foreign_folder_and_repeated_scenarios(tmp_path) -> None:
    (tmp_path / "features.txt").write_text("0.2 ID_001 1 2 0 0\n")  # a real dataset's file
    with pytest.raises(ValueError, match=r"expected a folder of generated datasets .*features.txt"):
        generate_sources([SyntheticSource("mingle", episodes=1)], root=tmp_path, seed=0)
    (tmp_path / "features.txt").unlink()
    with pytest.raises(ValueError, match="sources must each have their own name"):
        source = SyntheticSource("mingle", episodes=1)
        generate_sources([source, dataclasses.replace(source)], root=tmp_path, seed=0)


def test_two_sources_of_one_scenario_come_back_under_their_names(tmp_path) -> None:
    plain = SyntheticSource("mingle", episodes=1, duration=20.0, rate=0.5, options={"people": 8})
    close = dataclasses.replace(plain, options={"people": 8, "spacing": 0.46}, name="close")
    assert plain.name == "mingle" and plain.to_json()["name"] == "mingle"
    out = generate_sources([plain, close], root=tmp_path, seed=0, progress=False)
    assert list(out) == ["mingle", "close"]
    assert plain.folder(0) != close.folder(0)
    assert len(out["mingle"]) == len(out["close"]) == 10  # 20 s at 0.5 Hz
    # Each its own party: the closer bodies stand elsewhere.
    assert not np.array_equal(out["mingle"][-1].position, out["close"][-1].position)


def test_source_annotation_is_checked_and_names_its_folder() -> None:
    plain = SyntheticSource("mingle", episodes=1)
    coded = SyntheticSource("mingle", episodes=1, annotation={"directions": 8})
    drawn = SyntheticSource("mingle", episodes=1, annotation="random")
    assert len({plain.folder(0), coded.folder(0), drawn.folder(0)}) == 3
    assert coded.to_json()["annotation"] == {"directions": 8}
    with pytest.raises(ValueError, match="directions"):
        SyntheticSource("mingle", episodes=1, annotation={"directions": 0})
    with pytest.raises(ValueError, match="annotation must be None, 'random' or a mapping"):
        SyntheticSource("mingle", episodes=1, annotation="sometimes")


def test_nearest_neighbour_quantiles() -> None:
    from reform import Frame
    from sim.experiments.synthetic import nearest_neighbour_quantiles

    # Hand-computed: people at x = 0, 1, 3 m; nearest neighbours 1, 1, 2 m.
    frame = Frame(
        ids=np.array([1, 2, 3]),
        position=np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]]),
        yaw=np.zeros(3),
        groups=((1, 2), (3,)),
    )
    q10, q25, q50 = nearest_neighbour_quantiles([frame])
    assert q50 == pytest.approx(1.0) and q10 == pytest.approx(1.0)
    with pytest.raises(ValueError, match="at least one frame of two or more people"):
        nearest_neighbour_quantiles([])


def test_joint_distances(party) -> None:
    from sim.experiments.synthetic import joint_distances

    assert joint_distances(party, party) == (0.0, 0.0)
    spread = [f.replace(position=f.position * 10.0) for f in party]  # every pair 10 x apart
    tv_in, tv_out = joint_distances(spread, party)
    assert tv_in > 0.9 and 0.0 < tv_out <= 1.0
