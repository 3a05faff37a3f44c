"""Cost of recording a simulated 35-minute, 7-person session to Rerun, against simulating it.

The session is the simulator's own: ``sim.episode.simulate_episode("word-improv", seed,
duration=2100, rate=R)`` (Babble's Word Improv Game: a moderator and six players, 35 minutes),
at 2 Hz (the simulator's default rate) and 10 Hz. Baseline, in the same process: that call
(scenario, MuJoCo rollout, ground truth, validated ``reform.Frame`` objects); for information
also the bare rollout, ``sim.episode.episode_blocks`` (pose blocks, no Frames).

Logged, each timed as the median of ``--repeats`` runs after one warm-up call (the first call in
a process also pays Rerun's one-off start-up; it is printed as the warm-up call):

* ``record_episode(path, ep.truth, events=ep.events)``: what ``reform-sim simulate --save``
  does; the goal is that this costs at most 20% of ``simulate_episode``;
* the same from the pose blocks (``FrameColumns.from_blocks``), against the bare rollout;
* with two real detections, REFORM (bagged trees, trained on another seed's episode) and GCFF
  (the paper's stride and MDL): once scoring them inside ``record_episode`` (``reform.evaluate``
  per detector) and once with the evaluations given. Detection and scoring times are printed
  apart; detection is never counted as logging;
* the robot-watching variant (``robot="watch"``, ``view="robot"``): the world, the robot's
  observed stream and field of view, REFORM and GCFF run on the observed stream, the events;
  against ``simulate_episode`` of that view (which adds the robot's sensor).

Also printed: the time of each logging stage, the file size per simulated minute, and people's
positions logged with one ``rec.log`` per frame against one ``send_columns`` (why logging is in
bulk).

    python benchmarks/bench_recording.py [--rates 2 10] [--repeats 5] [--seed 0] [--quick]

``--quick``: a 2-minute session at 2 Hz, REFORM trained on one minute, one repeat.

Results (2 cores, load average 1.0-1.2 from another process, rerun-sdk 0.41, medians of 5):

    35 min, 7 people                                   2 Hz (4,200 frames)  10 Hz (21,000 frames)
    simulate_episode, truth view                       0.413 s              1.146 s
    bare rollout, episode_blocks                       0.251 s              0.306 s
    record_episode, truth + events (simulate --save)   0.032 s  ratio 0.077 0.121 s  ratio 0.106
      from the blocks, against the bare rollout        0.028 s  ratio 0.111 0.079 s  ratio 0.259
    + REFORM + GCFF, scored inside (reform.evaluate)   0.077 s  ratio 0.187 0.321 s  ratio 0.280
    + REFORM + GCFF, evaluations given                 0.057 s  ratio 0.138 0.203 s  ratio 0.177
    robot watching: simulate_episode, view="robot"     1.861 s              8.197 s
      world, observed, field of view, REFORM + GCFF    0.123 s  ratio 0.066 0.517 s  ratio 0.063
    file size per simulated minute, truth + events     0.065 MB             0.342 MB
      robot session with detections                    0.160 MB             0.822 MB
    people's positions: rec.log per frame vs one send_columns      1.93 s vs 0.077 s (25x)

The goal (at most 20% of simulate_episode) is met at both rates, for the session as the
simulator writes it and for the robot-watching session with detections. Detections on the truth
view, scored inside record_episode, are not: two ``reform.evaluate`` calls alone take 0.12 s of
the 0.32 s at 10 Hz. Before logging was columnar (commit 5236d56), record_episode of the truth
session took 0.086 s (2 Hz, ratio 0.20) and 0.374 s (10 Hz, ratio 0.30) in the same conditions.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
from timing import BenchmarkParser, timed

from reform import Frame, Gcff, Reform, evaluate
from sim.episode import episode_blocks, simulate_episode
from sim.experiments.gcff import PAPER_MDL_M2, PAPER_STRIDE_M
from sim.recording import (
    FrameColumns,
    default_blueprint,
    log_events,
    log_frames,
    log_group_counts,
    log_group_events,
    log_groups,
    log_room,
    log_running_scores,
    open_recording,
    record_episode,
    room_bounds,
    stream_group_events,
)

SCENARIO = "word-improv"  # Babble's game: a moderator and six players
DURATION_S = 2100.0  # seconds: 35 minutes
TRAIN_DURATION_S = 600.0  # seconds of another seed's episode REFORM learns from
QUICK_DURATION_S = 120.0  # seconds of the session with --quick
QUICK_TRAIN_DURATION_S = 60.0  # seconds of the training episode with --quick
RATES_HZ = (2.0, 10.0)  # frame rates of the session
QUICK_RATES_HZ = (2.0,)  # frame rates of the session with --quick
TRAIN_RATE_HZ = 2.0  # frames per second of the training episode
GOAL = 0.20  # logging may cost at most this fraction of simulating
ROBOT_OPTIONS = {"robot": "watch"}  # the Directions Robot watches from a corner


def warm_timed(function: Callable[[], Any], repeats: int) -> tuple[float, float]:
    """(median seconds of ``repeats`` calls after a warm-up call, seconds of the warm-up)."""
    first = timed(function, 1).first
    return timed(function, repeats).median, first


def detect(frames: Sequence[Frame], reform: Reform) -> tuple[dict[str, list], dict[str, float]]:
    """REFORM's and GCFF's partitions of every frame, and the seconds each took."""
    out: dict[str, list] = {}
    seconds: dict[str, float] = {}
    for name, detector in (
        ("reform", reform),
        ("gcff", Gcff(stride=PAPER_STRIDE_M, mdl=PAPER_MDL_M2)),
    ):
        start = time.perf_counter()
        out[name] = detector.predict(frames)
        seconds[name] = time.perf_counter() - start
    return out, seconds


def stages(
    path: Path,
    world: Sequence[Frame],
    observed: Sequence[Frame] | None,
    found: Mapping[str, list],
    evaluations: Mapping[str, Any],
    events: Sequence[object],
) -> dict[str, float]:
    """Seconds per logging stage of one recording (evaluations given), as record_episode runs."""
    out: dict[str, float] = {}
    start = time.perf_counter()
    columns = FrameColumns.of(world)
    seen = None if observed is None else FrameColumns.of(observed)
    detected_on = columns if seen is None else seen
    out["read the frames into columns"] = time.perf_counter() - start
    bounds = room_bounds(columns)
    counts = [len(f.fformations()) for f in world]
    blueprint = default_blueprint(scores=True, max_groups=max(counts, default=0), bounds=bounds)
    with open_recording(path, name="stages", seed=0, blueprint=blueprint) as rec:
        start = time.perf_counter()
        clock = log_frames(rec, columns, observed=seen)
        log_room(rec, bounds)
        out["people, robot, trails, field of view, observed"] = time.perf_counter() - start
        start = time.perf_counter()
        truth = log_groups(rec, columns, clock=clock)
        out["groups: truth"] = time.perf_counter() - start
        start = time.perf_counter()
        trees = {"truth": truth}
        for layer, (name, partitions) in enumerate(found.items(), start=1):
            first = 1 + max(int(t.tracks.max(initial=0)) for t in trees.values())
            trees[name] = log_groups(
                rec,
                detected_on,
                partitions,
                name=name,
                clock=clock,
                evaluation=evaluations[name],
                truth=truth,
                layer=layer,
                first_track=first,
            )
        out[f"groups: {len(found)} detectors (mistakes, matched colours)"] = (
            time.perf_counter() - start
        )
        start = time.perf_counter()
        log_group_counts(rec, trees, clock=clock)
        log_running_scores(rec, evaluations, clock=clock)
        log_events(rec, events, clock=clock)
        log_group_events(rec, stream_group_events(columns), name="truth", clock=clock)
        for name, partitions in found.items():
            detected = stream_group_events(detected_on, list(partitions))
            log_group_events(rec, detected, name=name, clock=clock)
        out["counts, running scores, events"] = time.perf_counter() - start
        start = time.perf_counter()
    out["flush and close the file"] = time.perf_counter() - start
    return out


def per_frame_versus_columns(
    path_a: Path, path_b: Path, world: Sequence[Frame]
) -> tuple[float, float]:
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


def verdict(ratio: float) -> str:
    return f"goal <= {GOAL:.2f}: {'met' if ratio <= GOAL else 'NOT met'}"


def bench_rate(
    rate: float,
    *,
    seed: int,
    duration: float,
    repeats: int,
    reform: Reform,
    tmp: Path,
    per_frame: bool,
) -> dict[str, float]:
    """Prints the figures of one frame rate; returns the ratios that have a goal."""
    kwargs = {"seed": seed, "duration": duration, "rate": rate}
    simulated = timed(lambda: simulate_episode(SCENARIO, **kwargs), repeats)
    rolled = timed(lambda: list(episode_blocks(SCENARIO, **kwargs)), repeats)
    t_sim, episode = simulated.median, simulated.result
    t_blocks, blocks = rolled.median, rolled.result
    world, events = episode.truth, episode.events
    minutes = len(world) / rate / 60.0
    people = sorted({int(i) for f in world for i in f.ids})
    print(
        f"\n== {rate:g} Hz: {len(world):,} frames, {minutes:.1f} simulated minutes, "
        f"{len(people)} people, {sum(f.groups is not None for f in world):,} annotated"
    )
    print(f"  simulate_episode (truth view)                          {t_sim:7.3f} s   baseline")
    print(f"  bare rollout, episode_blocks (pose blocks, no Frames)  {t_blocks:7.3f} s")

    path = tmp / f"truth-{rate:g}.rrd"
    t_log, t_first = warm_timed(
        lambda: record_episode(path, world, events=events, seed=seed), repeats
    )
    size = path.stat().st_size
    ratio = t_log / t_sim
    print(
        f"  record_episode: truth + events (simulate --save)       {t_log:7.3f} s   "
        f"ratio {ratio:.3f} of simulate_episode ({verdict(ratio)}), "
        f"{t_log / t_blocks:.3f} of the bare rollout; warm-up call {t_first:.3f} s"
    )
    t_cols, _ = warm_timed(
        lambda: record_episode(
            tmp / "blocks.rrd", FrameColumns.from_blocks(blocks), events=events, seed=seed
        ),
        repeats,
    )
    print(
        f"  the same from the blocks (FrameColumns.from_blocks)    {t_cols:7.3f} s   "
        f"ratio {t_cols / t_blocks:.3f} of the bare rollout"
    )

    found, t_detect = detect(world, reform)
    start = time.perf_counter()
    evaluations = {name: evaluate(world, partitions) for name, partitions in found.items()}
    t_score = time.perf_counter() - start
    detections_path = tmp / f"detections-{rate:g}.rrd"
    t_det_scored, _ = warm_timed(
        lambda: record_episode(detections_path, world, detections=found, events=events, seed=seed),
        repeats,
    )
    t_det_given, _ = warm_timed(
        lambda: record_episode(
            detections_path,
            world,
            detections=found,
            evaluations=evaluations,
            events=events,
            seed=seed,
        ),
        repeats,
    )
    print(
        f"  detection, not timed as logging: REFORM {t_detect['reform']:.2f} s, "
        f"GCFF {t_detect['gcff']:.2f} s; scoring both (reform.evaluate) {t_score:.3f} s"
    )
    ratios = {f"{rate:g} Hz  simulate --save: truth + events": ratio}
    for label, seconds in (
        ("+ REFORM + GCFF, scored inside record_episode", t_det_scored),
        ("+ REFORM + GCFF, evaluations given", t_det_given),
    ):
        r = seconds / t_sim
        ratios[f"{rate:g} Hz  truth view {label}"] = r
        print(f"  {label:53s}{seconds:7.3f} s   ratio {r:.3f} of simulate_episode ({verdict(r)})")

    robot_kwargs = {**kwargs, "view": "robot", "options": ROBOT_OPTIONS}
    robot_run = timed(lambda: simulate_episode(SCENARIO, **robot_kwargs), repeats)
    t_robot_sim, robot = robot_run.median, robot_run.result
    observed = robot.dataset.frames
    robot_found, robot_detect = detect(observed, reform)
    robot_path = tmp / f"robot-{rate:g}.rrd"
    t_robot, _ = warm_timed(
        lambda: record_episode(
            robot_path,
            robot.truth,
            observed=observed,
            detections=robot_found,
            events=robot.events,
            seed=seed,
        ),
        repeats,
    )
    robot_size = robot_path.stat().st_size
    r = t_robot / t_robot_sim
    ratios[f"{rate:g} Hz  robot watching: world, observed, field of view, detections"] = r
    print(
        f"  robot watching (view='robot'): simulate_episode       {t_robot_sim:7.3f} s   "
        f"baseline (REFORM {robot_detect['reform']:.2f} s, GCFF {robot_detect['gcff']:.2f} s "
        "on the observed stream, not timed)"
    )
    print(
        f"  record_episode: world, observed, field of view, REFORM + GCFF scored, events "
        f"{t_robot:.3f} s   ratio {r:.3f} ({verdict(r)})"
    )
    print(
        f"  file size per simulated minute: {size / minutes / 1e6:.3f} MB truth + events "
        f"({size / 1e6:.1f} MB), {robot_size / minutes / 1e6:.3f} MB robot session with "
        f"detections ({robot_size / 1e6:.1f} MB)"
    )
    robot_evaluations = {n: evaluate(observed, p) for n, p in robot_found.items()}
    runs = [
        stages(
            tmp / "stages.rrd",
            robot.truth,
            observed,
            robot_found,
            robot_evaluations,
            robot.events,
        )
        for _ in range(repeats)
    ]
    print("  stages of the robot session's recording (evaluations given), medians:")
    for stage in runs[0]:
        seconds = statistics.median(run[stage] for run in runs)
        print(f"    {stage:51s}{seconds * 1000:8.1f} ms")
    if per_frame:
        t_per_frame, t_columns = per_frame_versus_columns(
            tmp / "per-frame.rrd", tmp / "columns.rrd", world
        )
        print(
            f"  people's positions, {len(world):,} frames: one rec.log per frame "
            f"{t_per_frame:.2f} s vs one send_columns {t_columns:.3f} s "
            f"({t_per_frame / t_columns:.0f}x)"
        )
    return ratios


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=5)
    parser.add_sized(
        "--rates",
        default=RATES_HZ,
        quick=QUICK_RATES_HZ,
        help="frame rates, Hz",
        type=float,
        nargs="+",
    )
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rates = list(args.rates)
    duration = QUICK_DURATION_S if args.quick else DURATION_S
    train_duration = QUICK_TRAIN_DURATION_S if args.quick else TRAIN_DURATION_S

    load = os.getloadavg()[0]
    print(
        f"{SCENARIO}, seed {args.seed}, {duration / 60:g} simulated minutes; medians of "
        f"{args.repeats}; load average {load:.2f} at the start"
    )
    start = time.perf_counter()
    training = simulate_episode(
        SCENARIO, seed=args.seed + 1, duration=train_duration, rate=TRAIN_RATE_HZ
    )
    reform = Reform().fit(training.truth).compile()  # the pace of a long run
    print(
        f"REFORM (bagged trees) trained on seed {args.seed + 1}'s {train_duration / 60:g} "
        f"minutes at {TRAIN_RATE_HZ:g} Hz in {time.perf_counter() - start:.1f} s"
    )
    ratios: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for rate in rates:
            ratios.update(
                bench_rate(
                    rate,
                    seed=args.seed,
                    duration=duration,
                    repeats=args.repeats,
                    reform=reform,
                    tmp=Path(tmp),
                    per_frame=rate == max(rates),
                )
            )
    session = {k: v for k, v in ratios.items() if "truth view" not in k}
    extra = {k: v for k, v in ratios.items() if "truth view" in k}
    print(
        f"\nGoal: logging a simulated {duration / 60:g}-minute, 7-person session costs at most "
        f"{GOAL:.0%} of simulating it (logging / simulate_episode):"
    )
    for label, ratio in sorted(session.items(), key=lambda kv: "robot" in kv[0]):
        print(f"  {label:72s} {ratio:.3f}  {'met' if ratio <= GOAL else 'NOT met'}")
    print(
        "Also: detections on the truth view (a simulation without the robot's sensor to pay for):"
    )
    for label, ratio in extra.items():
        print(f"  {label:72s} {ratio:.3f}  {'met' if ratio <= GOAL else 'NOT met'}")
    met = all(r <= GOAL for r in session.values())
    at = " and ".join(f"{r:g} Hz" for r in rates)
    print(f"The goal is {'met' if met else 'NOT met'} at {at}.")


if __name__ == "__main__":
    main()
