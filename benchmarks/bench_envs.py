"""Environment speed: `SocialEnv.step` calls per second, beside the bare `World.step` they drive.

For 7 people (``ReformSim/WordImprov-v0``: six players and the moderator, the robot watching)
and 18 people (``ReformSim/Mingle-v0``: a SALSA-like party, the robot in the room), measured in
the same run on the same scenes:

* **env**: ``env.step(action)`` with seeded random actions: one 10 Hz control step moves the
  world by ten 100 Hz steps, reads the ground truth from MuJoCo, settles the scenario's
  ground-truth rule, takes the robot's view (field of view, ray-cast occlusion, noise draws),
  builds the observation, the task's geometry and reward terms, and every fifth step (2 Hz)
  runs GCFF on what the robot sees and scores it;
* **world**: ``World.step(10)`` on a world built from the same scenario, seed and script (the
  scenario's intents as the world's script, ``sim.episode.ScenarioScript``, as the environment
  builds it), and nothing else: the cost of moving the scene itself, the floor under any
  environment step.

Resets (making the scenario and the MuJoCo model) are timed apart. Prints medians over
``--repeats`` runs (and the best run, the least disturbed by other load on the machine); the
ratio env / world is the median of the ratios of runs made one after the other, so that a
change of load hits both alike. Target (issue 8): >= 2,000 env steps/s for 7 people.

Run: ``python benchmarks/bench_envs.py [--steps 600] [--repeats 5] [--quick]`` (``--quick``:
runs of 20 steps, one repeat).
"""

from __future__ import annotations

import statistics
import time

import gymnasium as gym
from timing import BenchmarkParser

import sim.envs  # noqa: F401  (registers the environments)
from sim import World
from sim.episode import ScenarioScript, scene_spec

SCENES = {7: "ReformSim/WordImprov-v0", 18: "ReformSim/Mingle-v0"}  # people -> environment
SEED = 20200915
TARGET_STEPS_PER_S = 2000.0  # env steps per second, 7 people
STEPS = 600  # control steps per timed run
QUICK_STEPS = 20  # control steps per timed run with --quick
WARM_UP_STEPS = 50  # control steps before timing (compiled kernels, caches)


def _env_run(env: gym.Env, seed: int, steps: int) -> tuple[float, float]:
    """Seconds for one reset and for ``steps`` steps (re-resetting when an episode ends)."""
    start = time.perf_counter()
    env.reset(seed=seed)
    reset_s = time.perf_counter() - start
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(steps)]
    spent = 0.0
    for action in actions:
        start = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(action)
        spent += time.perf_counter() - start
        if terminated or truncated:
            env.reset(seed=seed + 1)
    return reset_s, spent


def _world_run(env: gym.Env, seed: int, steps: int) -> float:
    """Seconds for ``steps`` bare control steps of a world made like the env's."""
    env.reset(seed=seed)
    base = env.unwrapped
    scenario = base.scenario
    world = World(
        scene_spec(scenario.stage, name=scenario.name),
        seed=seed,
        script=ScenarioScript(scenario),
    )
    world.step(10)  # compiled kernels warm
    start = time.perf_counter()
    for _ in range(steps):
        world.step(10)
    return time.perf_counter() - start


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=5)
    parser.add_sized("--steps", default=STEPS, quick=QUICK_STEPS, help="env steps per timed run")
    args = parser.parse_args()
    steps = args.steps

    print(f"{steps} control steps (10 Hz) per run, {args.repeats} runs, median (best)")
    print(
        f"{'people':>6} {'environment':<26} {'env steps/s':>18} {'World.step/s':>18} "
        f"{'env/world':>10} {'reset ms':>9}"
    )
    results = {}
    for people, env_id in SCENES.items():
        env = gym.make(env_id, disable_env_checker=True)
        _env_run(env, SEED, QUICK_STEPS if args.quick else WARM_UP_STEPS)  # warm-up
        env_rates, world_rates, ratios, resets = [], [], [], []
        for k in range(args.repeats):
            reset_s, env_s = _env_run(env, SEED + k, steps)
            world_s = _world_run(env, SEED + k, steps)
            env_rates.append(steps / env_s)
            world_rates.append(steps / world_s)
            ratios.append(env_s / world_s)
            resets.append(reset_s)
        env.close()
        rate = statistics.median(env_rates)
        results[people] = rate
        print(
            f"{people:>6} {env_id:<26} {rate:>9,.0f} ({max(env_rates):>6,.0f}) "
            f"{statistics.median(world_rates):>9,.0f} ({max(world_rates):>6,.0f}) "
            f"{statistics.median(ratios):>9.1f}x {1000 * statistics.median(resets):>9.0f}"
        )
    verdict = "met" if results[7] >= TARGET_STEPS_PER_S else "NOT met"
    print(
        f"target: >= {TARGET_STEPS_PER_S:,.0f} env steps/s with 7 people: {verdict} "
        f"({results[7]:,.0f}; {results[7] / 10:,.0f}x real time at 10 Hz)"
    )


if __name__ == "__main__":
    main()
