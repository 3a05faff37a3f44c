"""A crowd larger than a party: its twin is a concourse, fitted on who stands and who walks."""

from __future__ import annotations

import numpy as np
import pytest

from reform.frame import Frame
from sim.episode import simulate_episode
from sim.twins import TwinInputError, fit_twin, read_twin, write_twin
from sim.twins.data import twin_options
from sim.twins.fit import CROWD, SCENARIO, people_range
from sim.twins.statistics import STANDING_M_PER_S, standing_share

CROWD_PEOPLE = 150  # more than a mingle party holds


@pytest.fixture(scope="module")
def crowd(made_once):
    """A concourse of 150 recorded at 1 Hz for 60 s (with its groups), and its label-free twin
    (fitted once for every worker)."""
    frames = list(
        simulate_episode(
            CROWD, seed=5, rate=1.0, options={"people": CROWD_PEOPLE, "duration": 60.0}
        ).dataset
    )
    fitted = made_once(
        "hall-twin.json", lambda path: write_twin(fit_twin(frames, name="hall", n_jobs=2), path)
    )
    return frames, read_twin(fitted)


def _walkers(*, rate: float, speed: float, jitter: float = 0.0, n_frames: int = 40) -> list:
    """Four people standing and four walking east at ``speed``, at ``rate`` frames a second."""
    rng = np.random.default_rng(0)
    frames = []
    for k in range(n_frames):
        t = k / rate
        still = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
        moving = np.array([[speed * t, 3.0 + y] for y in range(4)])
        position = np.vstack([still, moving]) + rng.normal(0.0, jitter, size=(8, 2))
        frames.append(
            Frame(ids=np.arange(1, 9), position=position, yaw=np.zeros(8), time=t, sequence="s")
        )
    return frames


def test_more_people_than_a_party_holds_make_a_concourse_twin(crowd, tmp_path):
    frames, twin = crowd
    assert max(people_range(SCENARIO)) < CROWD_PEOPLE
    assert twin.scenario == CROWD
    rows = {row.name: row for row in twin.fitted}
    # as many people in a frame as the recording (walkers go out and come back: the twin's
    # people are more than a frame holds)
    assert twin.statistics["twin"]["people_median"] == pytest.approx(
        twin.statistics["real"]["people_median"], rel=0.15
    )
    assert twin.options["people"] >= twin.statistics["twin"]["people_median"]
    standing = rows["options.group_share"]
    assert standing.twin == pytest.approx(standing.real, abs=0.15)  # who stands, matched
    assert rows["scenario"].value == CROWD and rows["options.queue_share"].value == 0.0
    assert "options.hall_side" in rows and "options.max_group_size" in rows
    again = read_twin(write_twin(twin, tmp_path / "twin.json"))  # a valid twin file
    assert again.to_json() == twin.to_json()


def test_a_crowd_twin_never_reads_the_groups(crowd, tmp_path):
    frames, twin = crowd
    assert any(f.groups for f in frames)  # the recording has groups: the twin must not see them
    removed = [f.replace(groups=None, listed_groups=None) for f in frames]
    again = fit_twin(removed, name="hall", n_jobs=2)
    one, two = write_twin(twin, tmp_path / "1.json"), write_twin(again, tmp_path / "2.json")
    assert one.read_bytes() == two.read_bytes()


@pytest.mark.parametrize("more", [1, 2])
def test_a_crowd_twins_hall_holds_another_seeds_episodes_unchanged(crowd, more):
    # the hall is sized for its people, not for one draw of its groups: other seeds fit it as
    # fitted (a party's room that grows for another seed: test_twin_generate)
    _, twin = crowd
    options, said = twin_options(twin, seed=twin.seed + more, episodes=twin.episodes + more)
    assert (options, said) == (dict(twin.options), "")


def test_a_crowd_past_the_largest_concourse_is_refused_before_any_work():
    most = people_range(CROWD)[1]
    n = most + 1
    side = int(np.ceil(np.sqrt(n)))
    grid = np.array([(x, y) for x in range(side) for y in range(side)][:n], dtype=float)
    frames = [
        Frame(ids=np.arange(1, n + 1), position=grid, yaw=np.zeros(n), time=float(t), sequence="s")
        for t in range(10)
    ]
    with pytest.raises(
        TwinInputError,
        match=rf"^hall: field ids: expected at most {most} humans per frame .* found {n}$",
    ):
        fit_twin(frames, name="hall")


@pytest.mark.parametrize("rate", [0.5, 2.0, 25.0])
def test_standing_is_slower_than_a_walk_over_a_second_at_any_rate(rate):
    assert standing_share(_walkers(rate=rate, speed=1.2, jitter=0.01)) == pytest.approx(0.5)
    assert standing_share(_walkers(rate=rate, speed=STANDING_M_PER_S / 3)) == pytest.approx(1.0)


def test_no_one_seen_twice_a_second_apart_says_nothing():
    frames = _walkers(rate=0.1, speed=1.0)  # 10 s between frames: more than three
    assert np.isnan(standing_share(frames))
