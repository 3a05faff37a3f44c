"""The concourse: walkers crossing, a queue, groups aside; its ground truth, its refusals and its
recording (a crowd's level of detail), on real MuJoCo episodes of 150 people."""

from __future__ import annotations

import re

import numpy as np
import pytest
from rerun.chunk import RrdReader

import scenarios
from scenarios.concourse import ConcourseParams
from sim.episode import Episode, simulate_episode
from sim.recording import CROWD_PEOPLE, record_episode

OPTIONS = {"people": 150, "duration": 30.0}
SEED = 4


@pytest.fixture(scope="module")
def episode() -> Episode:
    return simulate_episode("concourse", seed=SEED, options=OPTIONS)


def _parts(episode: Episode) -> dict[int, str]:
    return {p.id: p.part for p in episode.scenario.stage.people}


def test_everyone_plays_a_part_in_the_declared_shares(episode):
    parts = list(_parts(episode).values())
    assert len(parts) == 150
    assert parts.count("guest") == 90 and parts.count("queuer") == 15  # 0.6 and 0.1 of 150
    assert parts.count("walker") == 45
    assert episode.scenario.stage.furniture[0].kind == "bar"  # the queue's counter
    option = scenarios.describe("concourse").option("people")
    assert option.default == 300 and (option.range.low, option.range.high) == (50, 3000)
    assert "crowd" in scenarios.describe("concourse").tags


def test_only_guests_stand_in_groups_and_groups_form(episode):
    """Walkers and queuers are never in a conversational group: a queue is no F-formation."""
    parts = _parts(episode)
    frames = episode.dataset.frames
    grouped = [m for f in frames for g in f.groups for m in g if len(g) >= 2]
    assert grouped and {parts[m] for m in grouped} == {"guest"}
    assert min(sum(len(g) >= 2 for g in f.groups) for f in frames[10:]) >= 5


def test_walkers_come_and_go_and_the_queue_moves_up(episode):
    parts = _parts(episode)
    frames = episode.dataset.frames
    walkers = [m for m, p in parts.items() if p == "walker"]
    present = np.array([[m in f.ids for m in walkers] for f in frames])
    assert present.any(axis=0).sum() > 10  # walkers came in ...
    assert (present[:-1] & ~present[1:]).any()  # ... and some left through an entrance
    served = [e for e in episode.events if e.kind == "served"]
    assert served and all(e.kind == "queue" for e in episode.events if "comes in" in e.detail)
    head = int(served[0].detail.split()[1])  # "person 97 is served ..."
    assert parts[head] == "queuer"
    at = [f.position[f.index_of(head)] for f in frames if head in f.ids]
    assert np.hypot(*(at[-1] - at[0])) > 1.0  # the served walked away from the counter


def test_same_seed_same_episode(episode):
    again = simulate_episode("concourse", seed=SEED, options=OPTIONS, duration=5.0)
    assert list(again.dataset.frames) == list(episode.dataset.frames[:10])


@pytest.mark.parametrize(
    ("options", "match"),
    [
        (
            {"people": 3000, "hall_side": 30.0},
            r"^concourse: 3000 people do not fit a 30 m x 30 m hall at a sane density \(.*\), "
            r"i\.e\. \d+ people; give a hall_side of at least \d+ m$",
        ),
        (
            {"people": 3000, "group_share": 0.0, "queue_share": 0.0},
            r"^concourse: 3000 people do not fit the largest hall \(100 m x 100 m\) at a sane "
            r"density \(.*\), i\.e\. (\d+) people; give people \1 or fewer$",
        ),
        (
            {"group_share": 0.7, "queue_share": 0.4},
            r"^concourse: options group_share and queue_share must add up to at most 1, got "
            r"0\.7 \+ 0\.4$",
        ),
        ({"people": 4000}, r"^concourse: option people must be within \[50, 3000\], got 4000$"),
        (
            {"people": 3000, "max_group_size": 2, "duration": 5.0},
            r"^concourse: no floor found for the drawn groups \(seed 0\): 1800 people in groups "
            r"of at most 2 do not fit 3 corners of 40 m \(100 m hall\); give fewer people, a "
            r"smaller group_share or a larger max_group_size$",
        ),
    ],
    ids=[
        "hall-too-small",
        "largest-hall-too-small",
        "shares-beyond-one",
        "people-out-of-range",
        "pairs-past-the-largest-hall",
    ],
)
def test_a_crowd_that_cannot_fit_is_refused_in_one_line(options, match):
    with pytest.raises(ValueError, match=match) as refused:
        scenarios.make("concourse", seed=0, **options)
    assert "\n" not in str(refused.value)


def test_the_size_named_as_fitting_fits():
    """The refusal's sizes are the truth: the people it says fit do (their parties are laid
    out), one more does not, and the hall side it asks for holds the crowd."""
    with pytest.raises(ValueError) as refused:
        ConcourseParams(people=1500, hall_side=40.0).check("concourse")
    found = re.search(
        r"i\.e\. (\d+) people; give a hall_side of at least (\d+) m$", str(refused.value)
    )
    most, side = int(found[1]), float(found[2])
    made = scenarios.make("concourse", seed=1, people=most, hall_side=40.0, duration=5.0)
    assert len(made.stage.people) == most and made.stage.room == (40.0, 40.0)
    with pytest.raises(ValueError, match=f"^concourse: {most + 1} people do not fit"):
        ConcourseParams(people=most + 1, hall_side=40.0).check("concourse")
    ConcourseParams(people=1500, hall_side=side).check("concourse")
    with pytest.raises(ValueError, match="1500 people do not fit"):
        ConcourseParams(people=1500, hall_side=side - 1.0).check("concourse")


def test_a_crowds_recording_batches_its_people(episode, tmp_path):
    """Beyond CROWD_PEOPLE people, no entity per MuJoCo body: the people are one batched
    entity holding everyone present in each frame; the room's geometry is still logged."""
    assert len(episode.scenario.stage.people) > CROWD_PEOPLE
    path = tmp_path / "concourse.rrd"
    record_episode(path, episode.truth, events=episode.events, model=episode.model, seed=SEED)
    chunks = list(RrdReader(path).stream().collect().stream())
    entities = {str(c.entity_path) for c in chunks}
    assert not [e for e in entities if e.startswith("/world/model/person")]
    assert "/world/model/world/boxes" in entities  # walls and the counter
    assert len(entities) < 30
    counts = {}  # frame -> capsules drawn
    for chunk in chunks:
        if str(chunk.entity_path) != "/world/people/bodies":
            continue
        data = chunk.to_record_batch().to_pydict()
        if "Capsules3D:translations" in data:
            for frame, row in zip(data["frame"], data["Capsules3D:translations"], strict=True):
                counts[frame] = len(row)
    assert [counts[k] for k in sorted(counts)] == [len(f.ids) for f in episode.truth]
