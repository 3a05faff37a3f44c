"""Cost of recording a 35-minute, 7-person session to Rerun, against the cost of its frames.

The session is a synthetic Word-Improv-Game episode (Babble's scene: a moderator and six players
in a circle in a 5 m x 5 m area; 30 s turns, a 5 s shuffle after each, a player eliminated
every fourth turn) with the Directions Robot watching from the side. World frames come at
10 Hz, smooth enough to watch the people move; ground truth every 0.5 s (every 5th frame), as
Babble is annotated. The robot's observed stream adds position noise and dropouts; two
detections (a near-perfect one and one that merges and splits groups) stand in for REFORM and
GCFF. Any iterable of ``reform.Frame`` works in place of the synthetic session: pass
``--parquet`` with frames written by ``reform.datasets.write_parquet`` (e.g. by the simulator).

Baseline, in the same process: producing the session's frames (generating the poses and
building the validated ``reform.Frame`` objects). Printed: medians of ``--repeats`` runs, the
ratio logging / frames, the time of each logging stage, the file size per simulated minute, and
per-frame ``rec.log`` against one ``send_columns`` for the same data (why logging is in bulk).

    python benchmarks/bench_recording.py [--minutes 35] [--repeats 3] [--parquet FRAMES]
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import rerun as rr

from reform import Frame
from sim.recording import (
    Event,
    default_blueprint,
    log_events,
    log_frames,
    log_group_counts,
    log_groups,
    log_running_scores,
    open_recording,
    record_episode,
)

RATE_HZ = 10.0  # world frames per second
ANNOTATION_EVERY = 5  # ground truth every 5th frame: 0.5 s, Babble's annotation rate
N_PEOPLE = 7  # a moderator and six players
ROBOT_ID = 100
TURN_S = 30.0  # seconds per turn
SHUFFLE_S = 5.0  # seconds of shuffling after each turn
ELIMINATE_EVERY = 4  # turns between eliminations
CIRCLE_RADIUS_M = 1.1  # metres
CENTRE = np.array([2.5, 2.5])  # metres: the middle of the 5 m x 5 m area
NOISE_M = 0.05  # metres: the sensor's position noise
DROPOUT = 0.05  # probability that the sensor misses a person in a frame


def babble_session(minutes: float, *, seed: int) -> tuple[list[Frame], list[Event]]:
    """World frames and scenario events of a synthetic Word Improv Game."""
    rng = np.random.default_rng(seed)
    n_frames = int(round(minutes * 60.0 * RATE_HZ))
    players = list(range(N_PEOPLE))
    places = np.arange(N_PEOPLE)  # slot of each person on the circle
    position = np.zeros((N_PEOPLE, 2))
    out_spot = {}
    events: list[Event] = []
    frames: list[Frame] = []
    cycle = TURN_S + SHUFFLE_S
    turn = -1
    start_pos = end_pos = None
    for k in range(n_frames):
        t = k / RATE_HZ
        phase = t % cycle
        if int(t // cycle) != turn:
            turn = int(t // cycle)
            events.append(Event(t, f"turn {turn + 1} starts"))
            if turn and turn % ELIMINATE_EVERY == 0 and len(players) > 2:
                leaver = int(rng.choice(players[1:]))
                players.remove(leaver)
                out_spot[leaver] = np.array([0.3 + 0.6 * len(out_spot), 0.3])
                events.append(Event(t, f"player {leaver} is eliminated", level="WARN"))
        in_circle = np.array(players)
        slots = np.argsort(np.argsort(places[in_circle]))
        angles = 2.0 * np.pi * slots / len(players)
        target = CENTRE + CIRCLE_RADIUS_M * np.column_stack([np.cos(angles), np.sin(angles)])
        shuffling = phase >= TURN_S
        if shuffling and start_pos is None:
            events.append(Event(t, "shuffle"))
            places[in_circle[1:]] = rng.permutation(places[in_circle[1:]])
            slots = np.argsort(np.argsort(places[in_circle]))
            angles = 2.0 * np.pi * slots / len(players)
            start_pos = position[in_circle].copy()
            end_pos = CENTRE + CIRCLE_RADIUS_M * np.column_stack([np.cos(angles), np.sin(angles)])
        if shuffling:
            s = (phase - TURN_S) / SHUFFLE_S
            position[in_circle] = (1 - s) * start_pos + s * end_pos
        else:
            start_pos = None
            position[in_circle] = target + rng.normal(0.0, 0.02, (len(players), 2))
        for leaver, spot in out_spot.items():
            position[leaver] = spot + rng.normal(0.0, 0.01, 2)
        towards = CENTRE - position
        yaw = np.arctan2(towards[:, 1], towards[:, 0]) + rng.normal(0.0, 0.1, N_PEOPLE)
        speaker = players[(k // int(5 * RATE_HZ)) % len(players)]
        look = position[speaker] - position
        head_yaw = np.where(
            np.arange(N_PEOPLE) == speaker, yaw, np.arctan2(look[:, 1], look[:, 0])
        ) + rng.normal(0.0, 0.05, N_PEOPLE)
        groups = None
        if k % ANNOTATION_EVERY == 0:
            groups = () if shuffling else (tuple(int(p) for p in players),)
        robot = np.array([[2.5, -0.5]])
        frames.append(
            Frame(
                ids=[*range(N_PEOPLE), ROBOT_ID],
                position=np.vstack([position, robot]),
                yaw=_wrap(np.append(yaw, math.pi / 2)),
                kinds=["human"] * N_PEOPLE + ["robot"],
                head_position=np.vstack([position, robot]),
                head_yaw=_wrap(np.append(head_yaw, math.pi / 2)),
                groups=groups,
                time=round(t, 6),
                sequence="babble-synthetic",
            )
        )
    return frames, events


def _wrap(theta: np.ndarray) -> np.ndarray:
    return (theta + np.pi) % (2.0 * np.pi) - np.pi


def observe(frames: list[Frame], *, seed: int) -> list[Frame]:
    """The robot's view: noisy positions, dropouts, ground truth restricted to who is seen."""
    rng = np.random.default_rng(seed)
    out = []
    for frame in frames:
        keep = (rng.random(frame.n_people) >= DROPOUT) | frame.is_robot
        seen = set(frame.ids[keep].tolist())
        groups = None
        if frame.groups is not None:
            groups = tuple(
                g for g in (tuple(m for m in grp if m in seen) for grp in frame.groups) if g
            )
        n = int(keep.sum())
        out.append(
            Frame(
                ids=frame.ids[keep],
                position=frame.position[keep] + rng.normal(0.0, NOISE_M, (n, 2)),
                yaw=_wrap(frame.yaw[keep] + rng.normal(0.0, 0.1, n)),
                kinds=[k for k, m in zip(frame.kinds, keep, strict=True) if m],
                groups=groups,
                time=frame.time,
                sequence=frame.sequence,
            )
        )
    return out


def detections(observed: list[Frame], *, seed: int) -> dict[str, list[tuple[tuple[int, ...], ...]]]:
    """Two stand-in detectors: 'reform' right 95% of the time, 'gcff' splitting big groups."""
    rng = np.random.default_rng(seed)
    good, split = [], []
    previous: tuple[tuple[int, ...], ...] | None = None
    for frame in observed:
        ids = frame.ids.tolist()
        humans = [i for i, r in zip(ids, frame.is_robot.tolist(), strict=True) if not r]
        truth = frame.partition() if frame.groups is not None else previous
        if truth is None or set(m for g in truth for m in g) != set(ids):
            truth = tuple((i,) for i in ids)
        previous = truth
        good.append(truth if rng.random() < 0.95 else tuple((i,) for i in ids))
        half = len(humans) // 2
        halves = (tuple(humans[:half]), tuple(humans[half:]))
        split.append(tuple(g for g in halves if g) + tuple((i,) for i in ids if i not in humans))
    return {"reform": good, "gcff": split}


def median(function, repeats: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def stages(path: Path, world, observed, found, events) -> dict[str, float]:
    """Seconds per logging stage, one run."""
    out: dict[str, float] = {}
    with open_recording(path, name="stages", seed=0, blueprint=default_blueprint()) as rec:
        start = time.perf_counter()
        clock = log_frames(rec, world, observed=observed)
        out["people, robot, trails, observed"] = time.perf_counter() - start
        start = time.perf_counter()
        truth = log_groups(rec, world, clock=clock)
        out["groups: truth"] = time.perf_counter() - start
        start = time.perf_counter()
        trees = {"truth": truth}
        for name, partitions in found.items():
            trees[name] = log_groups(rec, observed, partitions, name=name, clock=clock, truth=truth)
        out["groups: 2 detectors (with evaluation, mistakes)"] = time.perf_counter() - start
        start = time.perf_counter()
        log_group_counts(rec, trees, clock=clock)
        log_running_scores(
            rec,
            {n: t.evaluation for n, t in trees.items() if n != "truth"},
            {n: observed for n in found},
            clock=clock,
        )
        log_events(rec, events, clock=clock)
        out["scores, counts, events"] = time.perf_counter() - start
        start = time.perf_counter()
    out["flush and close"] = time.perf_counter() - start
    return out


def per_frame_versus_columns(path_a: Path, path_b: Path, world: list[Frame]) -> tuple[float, float]:
    """The people's positions and ids logged with one rec.log per frame vs one send_columns."""
    start = time.perf_counter()
    with open_recording(path_a, name="per-frame") as rec:
        for k, frame in enumerate(world):
            rec.set_time("frame", sequence=k)
            rec.set_time("sim_time", duration=frame.time)
            xyz = np.column_stack([frame.position, np.zeros(frame.n_people)])
            rec.log("world/people/labels", rr.Points3D(xyz, class_ids=frame.ids.astype(np.uint16)))
    per_frame = time.perf_counter() - start
    start = time.perf_counter()
    with open_recording(path_b, name="columns") as rec:
        counts = np.array([f.n_people for f in world])
        xyz = np.column_stack([np.concatenate([f.position for f in world]), np.zeros(counts.sum())])
        ids = np.concatenate([f.ids for f in world]).astype(np.uint16)
        rec.send_columns(
            "world/people/labels",
            indexes=[
                rr.TimeColumn("frame", sequence=np.arange(len(world))),
                rr.TimeColumn("sim_time", duration=[f.time for f in world]),
            ],
            columns=rr.Points3D.columns(positions=xyz, class_ids=ids).partition(counts),
        )
    return per_frame, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=35.0, help="simulated minutes")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--parquet", default=None, help="frames to record instead (Parquet)")
    args = parser.parse_args()

    if args.parquet:
        from reform.datasets import read_parquet

        t_frames, dataset = median(lambda: read_parquet(args.parquet), args.repeats)
        world, events = list(dataset.frames), []
        baseline = "reading the Parquet frames"
    else:
        t_frames, (world, events) = median(
            lambda: babble_session(args.minutes, seed=args.seed), args.repeats
        )
        baseline = "producing the frames (poses + validated Frames)"
    observed = observe(world, seed=args.seed + 1)
    found = detections(observed, seed=args.seed + 2)
    minutes = (world[-1].time - world[0].time) / 60.0 + 1.0 / (60.0 * RATE_HZ)

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "session.rrd"
        t_log, _ = median(
            lambda: record_episode(
                path, world, observed=observed, detections=found, events=events, seed=args.seed
            ),
            args.repeats,
        )
        size = path.stat().st_size
        breakdown = stages(Path(tmp) / "stages.rrd", world, observed, found, events)
        t_per_frame, t_columns = per_frame_versus_columns(
            Path(tmp) / "a.rrd", Path(tmp) / "b.rrd", world
        )

    print(
        f"session: {minutes:.1f} simulated minutes, {len(world):,} frames at {RATE_HZ:g} Hz, "
        f"{N_PEOPLE} people + robot, {sum(f.groups is not None for f in world):,} annotated"
    )
    print(f"baseline  {baseline}: {t_frames:8.2f} s  (median of {args.repeats})")
    print(
        f"recording record_episode (world, observed, 2 detectors, events): {t_log:8.2f} s"
        f"  ratio {t_log / t_frames:.2f}x the baseline"
    )
    print(
        f"          per simulated minute: {t_log / minutes * 1000:.0f} ms, "
        f"{size / minutes / 1e6:.2f} MB ({size / 1e6:.1f} MB in all)"
    )
    for stage, seconds in breakdown.items():
        print(f"  stage {stage:48s} {seconds:7.2f} s")
    print(
        f"bulk      people positions: per-frame rec.log {t_per_frame:.2f} s vs one send_columns "
        f"{t_columns:.3f} s ({t_per_frame / t_columns:.0f}x)"
    )


if __name__ == "__main__":
    main()
