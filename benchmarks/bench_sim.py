"""Simulation speed: simulated seconds per wall-clock second, beside a bare MuJoCo loop.

For 7, 18 and 50 people (and the robot) wandering a room at 100 Hz pose output, measured in the
same run on the same compiled model:

* **bare**: ``mujoco.mj_kinematics(model, data)`` in a Python loop over the scene's model
  (``World.model``), once per 100 Hz step, and nothing else (no motion, no output): the floor a
  Python-driven kinematic world stands on. The same loop over the scene's kinematic twin (the
  model ``World.rollout`` computes poses on: same bodies and joints, one geom per body) is
  printed too, with the rollout's ratio to it;
* **rollout**: ``World.rollout(..., rate=100)``: the script sampled at 10 Hz, the compiled motion
  kernel (walking, avoidance, personal space, head, sway) at 100 Hz, MuJoCo's ``mj_kinematics``
  for every step (called from the compiled loop), body and head poses read back as
  `reform.FrameBlock`;
* **frames**: ``World.run(..., rate=100)``: the same, one `reform.Frame` per step (validated
  records; this path is meant for annotation rates of a few hertz);
* with ``--threads 2``, the rollout again with each block's kinematics in one ``mujoco.batch``
  call on two threads.

Then a one-hour run of 50 people streams 360,000 rows of poses through ``World.rollout`` and
reports the peak memory it traced (numpy allocations) next to the size of the whole run.

Prints medians over ``--repeats`` runs (and the best runs, the least disturbed by other load on
the machine); the ratio harness / bare (lower is better) is the median
of the ratios of runs made one after the other, so that a change of load hits both alike.
Target (issue 5): 18 people at >= 1,000x real time, harness <= 3x the bare loop.

Run: ``python benchmarks/bench_sim.py [--quick] [--repeats 5] [--threads 2] [--no-hour]``
(``--quick``: 2 s runs, two repeats, no hour run).
"""

from __future__ import annotations

import math
import statistics
import time
import tracemalloc
from collections.abc import Mapping

import mujoco
import numpy as np
from timing import BenchmarkParser

from sim import Intent, PersonSpec, RobotSpec, SceneSpec, World, build_scene

SIZES = (7, 18, 50)  # people per scene (plus the robot)
ROOMS_M = {7: 5.0, 18: 7.0, 50: 11.0}  # metres, side of the square room per size
SEED = 20200915
SIM_SECONDS = 60.0  # simulated seconds per timed run
QUICK_SIM_SECONDS = 2.0  # simulated seconds per timed run with --quick
RATE_HZ = 100.0  # pose output rate
HOUR_S = 3600.0  # seconds
TARGET_SPEED_18 = 1000.0  # x real time
TARGET_RATIO = 3.0  # harness / bare loop
GOAL_PERIOD_S = (4.0, 10.0)  # seconds between new goals, per person (uniform)


class Wander:
    """Each person walks to a new random spot every few seconds, looking at someone else.

    Pure function of time: the schedule is drawn once from the generator. The mapping returned
    only changes when someone's goal changes (the world skips unchanged intents).
    """

    def __init__(self, spec: SceneSpec, rng: np.random.Generator) -> None:
        people = spec.people
        self.ids = np.array([p.id for p in people])
        half = 0.5 * spec.room[0] - 0.6
        self.period = rng.uniform(*GOAL_PERIOD_S, size=len(people))
        self.offset = rng.uniform(0.0, 1.0, size=len(people)) * self.period
        self.goals = rng.uniform(-half, half, size=(2000, len(people), 2))
        self.gaze = rng.integers(0, len(people), size=(2000, len(people)))
        self.speed = rng.uniform(1.0, 1.4, size=(2000, len(people)))
        self.key: tuple[int, ...] | None = None
        self.mapping: dict[int, Intent] = {}
        self.valid_until = -math.inf  # seconds: the mapping holds until someone's goal changes
        self.cache: dict[tuple[int, int], Intent] = {}
        self.group_list = tuple(
            (int(a), int(b)) for a, b in zip(self.ids[0::2], self.ids[1::2], strict=False)
        )

    def _intent(self, i: int, k: int) -> Intent:
        if (i, k) not in self.cache:
            j = int(self.gaze[k, i])
            self.cache[(i, k)] = Intent(
                goal=(float(self.goals[k, i, 0]), float(self.goals[k, i, 1])),
                speed=float(self.speed[k, i]),
                gaze_agent=int(self.ids[j]) if j != i else None,
            )
        return self.cache[(i, k)]

    def intents(self, t: float) -> Mapping[int, Intent]:
        if self.key is not None and t < self.valid_until:
            return self.mapping
        phase = (t + self.offset) / self.period
        k = np.floor(phase).astype(int) % self.goals.shape[0]
        self.valid_until = float(np.min((np.floor(phase) + 1.0) * self.period - self.offset))
        key = tuple(k.tolist())
        if key != self.key:
            self.key = key
            self.mapping = {int(pid): self._intent(i, key[i]) for i, pid in enumerate(self.ids)}
        return self.mapping

    def groups(self, t: float) -> tuple[tuple[int, ...], ...]:
        return self.group_list


def scene(n: int) -> SceneSpec:
    """``n`` people on a grid in a square room, the robot in a corner."""
    side = ROOMS_M[n]
    cols = math.ceil(math.sqrt(n))
    spacing = (side - 2.0) / cols
    people = [
        PersonSpec(
            id=i + 1,
            position=(
                -side / 2 + 1.0 + spacing * (i % cols),
                -side / 2 + 1.0 + spacing * (i // cols),
            ),
            yaw=0.3 * i,
        )
        for i in range(n)
    ]
    robot = RobotSpec(id=0, position=(side / 2 - 0.5, side / 2 - 0.5), yaw=-2.3)
    return SceneSpec(people=people, robot=robot, room=(side, side))


def world_for(n: int) -> World:
    spec = scene(n)
    return World(spec, seed=SEED, script=Wander(spec, np.random.default_rng(SEED + n)))


def time_bare(model: mujoco.MjModel, steps: int) -> float:
    data = mujoco.MjData(model)
    kinematics = mujoco.mj_kinematics
    start = time.perf_counter()
    for _ in range(steps):
        kinematics(model, data)
    return time.perf_counter() - start


def time_rollout(n: int, seconds: float, threads: int = 1) -> float:
    world = world_for(n)
    start = time.perf_counter()
    rows = 0
    for block in world.rollout(seconds, rate=RATE_HZ, threads=threads):
        rows += len(block)
    elapsed = time.perf_counter() - start
    assert rows == round(seconds * RATE_HZ)
    return elapsed


def time_frames(n: int, seconds: float) -> float:
    world = world_for(n)
    start = time.perf_counter()
    count = sum(1 for _ in world.run(seconds, rate=RATE_HZ))
    elapsed = time.perf_counter() - start
    assert count == round(seconds * RATE_HZ)
    return elapsed


def hour_run(n: int) -> None:
    world = world_for(n)
    rows = 0
    tracemalloc.start()
    start = time.perf_counter()
    for block in world.rollout(HOUR_S, rate=RATE_HZ):
        rows += len(block)
    elapsed = time.perf_counter() - start
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    agents = n + 1
    whole = rows * agents * (2 + 1 + 2 + 1) * 8 + rows * agents  # float64 poses + presence
    print(
        f"\none hour, {n} people, {RATE_HZ:g} Hz: {rows} rows streamed in {elapsed:.1f} s "
        f"({HOUR_S / elapsed:,.0f}x real time); peak traced memory {peak / 2**20:.1f} MiB, "
        f"while the whole run's poses are {whole / 2**20:.0f} MiB"
    )


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=5, quick_repeats=2)
    parser.add_argument("--threads", type=int, default=1, help="also time the rollout on N threads")
    parser.add_argument("--no-hour", action="store_true", help="skip the one-hour 50-person run")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), choices=SIZES)
    args = parser.parse_args()
    seconds = QUICK_SIM_SECONDS if args.quick else SIM_SECONDS
    repeats = args.repeats
    steps = round(seconds * RATE_HZ)

    start = time.perf_counter()
    time_rollout(7, 0.1)  # compile or load the motion kernel
    print(f"motion kernel ready in {time.perf_counter() - start:.2f} s (numba; cached on disk)")
    print(
        f"simulated seconds per wall-clock second, {RATE_HZ:g} Hz poses, {seconds:g} s runs, "
        f"median of {repeats}"
    )
    header = f"{'people':>6} {'bare':>10} {'rollout':>10} {'ratio':>6} {'frames':>9} {'ratio':>6}"
    if args.threads > 1:
        header += f" {f'rollout x{args.threads}':>12} {'ratio':>6}"
    print(header)
    results = {}
    for n in args.sizes:
        world = world_for(n)
        model, twin = world.model, build_scene(world.spec, geometry=False)
        bare, bare_twin, roll, frames, threaded = [], [], [], [], []
        for r in range(repeats):  # interleaved, so that load changes hit both sides alike
            bare.append(time_bare(model, steps))
            bare_twin.append(time_bare(twin, steps))
            roll.append(time_rollout(n, seconds))
            if r < max(1, repeats // 2):
                frames.append(time_frames(n, seconds))
            if args.threads > 1:
                threaded.append(time_rollout(n, seconds, args.threads))

        def ratio(times: list[float], bare: list[float] = bare) -> float:
            return statistics.median(t / b for t, b in zip(times, bare, strict=False))

        def speed(times: list[float]) -> float:
            return seconds / statistics.median(times)

        line = (
            f"{n:>6} {speed(bare):>9,.0f}x {speed(roll):>9,.0f}x {ratio(roll):>6.2f} "
            f"{speed(frames):>8,.0f}x {ratio(frames):>6.2f}"
        )
        if args.threads > 1:
            line += f" {speed(threaded):>11,.0f}x {ratio(threaded):>6.2f}"
        line += (
            f"   (best runs: bare {seconds / min(bare):,.0f}x, rollout {seconds / min(roll):,.0f}x;"
            f" bare loop over the kinematic twin {speed(bare_twin):,.0f}x, rollout / it "
            f"{ratio(roll, bare_twin):.2f})"
        )
        print(line)
        results[n] = (speed(roll), ratio(roll))
    if 18 not in results:
        return
    speed, ratio = results[18]
    print(
        f"\n18 people: {speed:,.0f}x real time (target >= {TARGET_SPEED_18:,.0f}x), harness "
        f"{ratio:.2f}x the bare loop (target <= {TARGET_RATIO:g}x); a 35-minute session takes "
        f"{35 * 60 / speed:.2f} s"
    )
    if not (args.quick or args.no_hour):
        hour_run(50)


if __name__ == "__main__":
    main()
