"""The concourse at 1,000 people: simulated seconds per wall-clock second, beside bare MuJoCo.

One concourse (``scenarios.make("concourse", people=1000)``: walkers crossing, a queue, groups
standing aside) is simulated on one core for ``--seconds`` at the world's 100 Hz control rate,
poses written at 2 Hz as every episode writes them (``sim.episode.episode_blocks``). Measured in
the same run, on the same compiled model:

* **bare**: ``mujoco.mj_kinematics(model, data)`` in a Python loop over the world's own model
  (``World.rollout`` computes poses on it), once per 100 Hz step, nothing else: what MuJoCo's
  kinematics of this scene costs on its own;
* **rollout**: ``World.rollout``, the whole simulation: the script sampled at 10 Hz, the
  compiled motion kernel (walking, avoidance, personal space, head, sway) and ``mj_kinematics``
  at 100 Hz, the ground truth settled at every frame;
* **episode**: the same, plus drawing the scenario and composing its MuJoCo scene, as
  ``reform-sim simulate`` does.

Prints medians over ``--repeats`` runs, the bare loop and the rollout one after the other in
each, and rollout / bare as the median of each run's ratio. Target (issue 31): the rollout at
least 10x real time at 1,000 people.

Run: ``python benchmarks/bench_concourse.py [--quick] [--repeats 3] [--people 1000]
[--seconds 60]`` (``--quick``: 150 people, 5 s, one repeat).
"""

from __future__ import annotations

import statistics
import time

from bench_sim import time_bare
from timing import BenchmarkParser

import scenarios
from sim.episode import DEFAULT_RATE_HZ, ScenarioScript, scene_spec
from sim.world import DEFAULT_DT_S, World

SEED = 20261205
TARGET_SPEED = 10.0  # x real time at 1,000 people
TARGET_PEOPLE = 1000  # people of the target


def make_world(made: scenarios.Scenario) -> World:
    return World(
        scene_spec(made.stage, name=made.name),
        seed=SEED,
        script=ScenarioScript(made),
        truth=made.ground_truth(),
    )


def time_episode(people: int, seconds: float) -> tuple[float, float, World]:
    """(seconds to draw the scenario and build its world, seconds of the rollout, the world)."""
    start = time.perf_counter()
    made = scenarios.make("concourse", seed=SEED, people=people, duration=seconds)
    world = make_world(made)
    built = time.perf_counter()
    frames = sum(len(block) for block in world.rollout(seconds, rate=DEFAULT_RATE_HZ))
    rolled = time.perf_counter()
    assert frames == round(seconds * DEFAULT_RATE_HZ), frames
    assert world.step_count == round(seconds / DEFAULT_DT_S), world.step_count
    return built - start, rolled - built, world


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=3, quick_repeats=1)
    parser.add_sized("--people", default=1000, quick=150, help="people in the concourse")
    parser.add_sized(
        "--seconds", default=60.0, quick=5.0, type=float, help="simulated seconds per run"
    )
    args = parser.parse_args()
    steps = round(args.seconds / DEFAULT_DT_S)

    start = time.perf_counter()
    time_episode(60, 0.5)  # compile or load the motion kernel
    print(f"motion kernel ready in {time.perf_counter() - start:.2f} s (numba; cached on disk)")
    setup, rollout, bare = [], [], []
    for _ in range(args.repeats):
        built, rolled, world = time_episode(args.people, args.seconds)
        setup.append(built)
        rollout.append(rolled)
        bare.append(time_bare(world.model, steps))
    agents = len(world.spec.people)
    print(
        f"concourse, {agents} people ({world.model.nbody} MuJoCo bodies), {args.seconds:g} s "
        f"at {1 / DEFAULT_DT_S:g} Hz ({steps} steps), poses at {DEFAULT_RATE_HZ:g} Hz, one "
        f"core, median of {args.repeats}"
    )

    def speed(times: list[float]) -> float:
        return args.seconds / statistics.median(times)

    ratio = statistics.median(r / b for r, b in zip(rollout, bare, strict=True))
    episode = [s + r for s, r in zip(setup, rollout, strict=True)]
    print(f"bare mj_kinematics  {speed(bare):>8.1f}x real time")
    print(f"rollout             {speed(rollout):>8.1f}x real time   rollout / bare: {ratio:.2f}x")
    print(
        f"episode             {speed(episode):>8.1f}x real time   (drawing the scenario and "
        f"composing its scene: {statistics.median(setup):.2f} s)"
    )
    met = "met" if speed(rollout) >= TARGET_SPEED else "not met"
    if agents < TARGET_PEOPLE:
        met = f"fewer people than the target's {TARGET_PEOPLE:,}: not judged"
    print(
        f"Target: the rollout at >= {TARGET_SPEED:g}x real time at 1,000 people: "
        f"{speed(rollout):.1f}x at {agents} ({met})"
    )


if __name__ == "__main__":
    main()
