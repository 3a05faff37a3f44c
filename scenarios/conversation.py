"""Talk in a group: who speaks when, and heads turning to whoever speaks."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from scenarios.script import Intent
from scenarios.timeline import TimelineBuilder

__all__ = ["MEAN_UTTERANCE_S", "converse", "standing"]

MEAN_UTTERANCE_S = 4.0  # seconds, mean length of one person's turn to speak
MIN_UTTERANCE_S = 1.0  # seconds
MAX_UTTERANCE_FACTOR = 3.0  # an utterance lasts at most this many times the mean
_TRUSTED = 1e100  # metres or radians: below this, sums and products of a few stay finite


def standing(
    place: np.ndarray | tuple[float, float],
    facing: float,
    *,
    gaze_agent: int | None = None,
    gaze_point: tuple[float, float] | None = None,
    speed: float | None = None,
) -> Intent:
    """Stand at (walk to) ``place`` facing ``facing``, looking at someone or somewhere."""
    kwargs = {} if speed is None else {"speed": speed}
    return Intent(
        goal=(float(place[0]), float(place[1])),
        face_yaw=float(facing),
        gaze_agent=gaze_agent,
        gaze_point=gaze_point,
        **kwargs,
    )


def _sight(head: tuple[float, float], target: tuple[float, float]) -> tuple[float, float]:
    """(direction, reach) of a head at ``head`` looking at ``target``: the angle toward it,
    radians, and its distance, 0.5 m at least."""
    (hx, hy), (tx, ty) = head, target
    return math.atan2(ty - hy, tx - hx), max(math.hypot(tx - hx, ty - hy), 0.5)


def _off_target(
    head: tuple[float, float], target: tuple[float, float], drawn: float, head_noise: float
) -> tuple[float, float]:
    """Where a head at ``head`` looks, off ``target`` by ``drawn`` (a standard normal draw)
    times ``head_noise`` radians, at the target's distance (0.5 m at least)."""
    direction, reach = _sight(head, target)
    angle = direction + drawn * head_noise
    return (head[0] + reach * math.cos(angle), head[1] + reach * math.sin(angle))


def converse(
    builder: TimelineBuilder,
    members: Sequence[int],
    places: np.ndarray,
    facings: np.ndarray,
    *,
    start: float,
    end: float,
    rng: np.random.Generator,
    mean_utterance: float = MEAN_UTTERANCE_S,
    speakers: Sequence[int] | None = None,
    head_noise: float = 0.0,
    speed: float | Mapping[int, float] | None = None,
) -> list[tuple[float, int]]:
    """Members stand at their places and talk from ``start`` to ``end``, turn by turn.

    Each utterance lasts an exponential time (mean ``mean_utterance`` s, within
    [`MIN_UTTERANCE_S`, `MAX_UTTERANCE_FACTOR` x mean]); the next speaker is drawn among the
    others (``speakers`` restricts who may speak). Listeners look at the speaker; the speaker
    looks at one listener. ``head_noise`` (radians, standard deviation) turns each gaze off its
    target. ``speed`` (m/s, one for all or by member) is how fast members still on their way
    walk to their places.

    Returns:
        ``(time, speaker)`` of every utterance.
    """
    members = [int(m) for m in members]
    if isinstance(places, np.ndarray):  # read as Python numbers at once, not entry by entry
        places = places.tolist()
    if isinstance(facings, np.ndarray):
        facings = facings.tolist()
    spots = {m: (float(places[k][0]), float(places[k][1])) for k, m in enumerate(members)}
    facing = {m: float(facings[k]) for k, m in enumerate(members)}
    allowed = members if speakers is None else [int(s) for s in speakers]
    # Each member stands the same way all along: that intent is made (and checked) once, and
    # each turn gives it the turn's gaze (`Intent.looking_at`).
    t = float(start)
    by_member = isinstance(speed, Mapping)
    stand = {
        m: standing(spots[m], facing[m], speed=speed.get(m) if by_member else speed)
        for m in members
        if t < end
    }
    integers, normal, exponential = rng.integers, rng.normal, rng.exponential
    speaker = allowed[int(integers(len(allowed)))]
    turns = []
    if t >= end:
        return turns
    builder.check_agents(members)
    everyone = tuple(members)  # kept by the builder as it is, turn after turn
    shortest = MIN_UTTERANCE_S
    longest = MAX_UTTERANCE_FACTOR * mean_utterance
    size = len(members)
    # Who listens to each speaker and who may speak next, by speaker; by speaker and addressee,
    # whom each member looks at: the intents themselves when gazes are on target (made once),
    # else each member's sight of its target (direction and distance, computed once, as
    # `_off_target` computes them).
    listening: dict[int, list[int]] = {}
    next_ones: dict[int, list[int]] = {}
    rows: dict[tuple[int, int], list] = {}
    sights: dict[tuple[int, int], tuple] = {}  # by member and target
    # A gaze point made here from finite places, directions and draws is finite: it skips
    # `Intent.looking_at`'s check (a place too large to make one is checked as before).
    trusted = (
        math.isfinite(head_noise)
        and abs(head_noise) < _TRUSTED
        and all(abs(x) < _TRUSTED and abs(y) < _TRUSTED for x, y in spots.values())
    )
    on_target = head_noise <= 0.0
    looks = {m: {**stand[m].__dict__, "gaze_agent": None} for m in members}
    made = object.__new__
    while t < end:
        turns.append((t, speaker))
        listeners = listening.get(speaker)
        if listeners is None:
            listeners = listening[speaker] = [m for m in members if m != speaker]
        # ``integers(1)`` is 0 and draws nothing from the generator (numpy draws no bits for a
        # range of one value): in a pair, the call is skipped
        addressee = (
            listeners[0] if len(listeners) == 1 else listeners[int(integers(len(listeners)))]
        )
        # A standard normal draw per member, in member order, whatever the head noise (so
        # that the stream does not depend on it).
        noise = normal(size=size).tolist()
        if on_target or trusted:
            row = rows.get((speaker, addressee))
            if row is None:
                targets = [addressee if m == speaker else speaker for m in members]
                if on_target:
                    row = [
                        stand[m].looking_at(agent=x) for m, x in zip(members, targets, strict=True)
                    ]
                else:
                    row = []
                    for m, x in zip(members, targets, strict=True):
                        sight = sights.get((m, x))
                        if sight is None:
                            sight = sights[m, x] = (
                                looks[m],
                                *spots[m],
                                *_sight(spots[m], spots[x]),
                            )
                        row.append(sight)
                rows[speaker, addressee] = row
            if on_target:
                intents = row
            else:
                intents = []
                for (look, hx, hy, direction, reach), drawn in zip(row, noise, strict=True):
                    angle = direction + drawn * head_noise
                    intent = made(Intent)
                    fields = intent.__dict__
                    fields.update(look)
                    fields["gaze_point"] = (
                        hx + reach * math.cos(angle),
                        hy + reach * math.sin(angle),
                    )
                    intents.append(intent)
        else:
            intents = [
                stand[m].looking_at(
                    point=_off_target(
                        spots[m], spots[addressee if m == speaker else speaker], drawn, head_noise
                    )
                )
                for m, drawn in zip(members, noise, strict=True)
            ]
        builder.set_many(t, everyone, intents)
        length = exponential(mean_utterance)
        t += min(max(length, shortest), longest)
        others = next_ones.get(speaker)
        if others is None:
            others = next_ones[speaker] = [s for s in allowed if s != speaker] or allowed
        speaker = others[0] if len(others) == 1 else others[int(integers(len(others)))]
    return turns
