"""Gymnasium environments: the Directions Robot as the agent in scripted social scenes.

Importing this package registers, for every registered scenario with a place for the robot
(`scenarios.register`'s ``robot=``) but the randomised ones (whose room and crowd change with
the seed), one environment for the joining task and one for observing
(or name it in the id: ``gymnasium.make("sim.envs:ReformSim/Mingle-v0")``)::

    ReformSim/HRIConversation-v0    ReformSim/HRIConversationObserve-v0
    ReformSim/HRIPassing-v0         ReformSim/HRIPassingObserve-v0
    ReformSim/HRIRobotExcluded-v0   ReformSim/HRIRobotExcludedObserve-v0
    ReformSim/Mingle-v0             ReformSim/MingleObserve-v0
    ReformSim/WordImprov-v0         ReformSim/WordImprovObserve-v0

``gymnasium.make(id, **kwargs)`` passes keyword arguments on to `SocialEnv` (``detector=``,
``model=``, ``sensor=``, ``render_mode="rgb_array"`` or ``"human"``, ``record_dir=``, ...).
Registration imports only gymnasium and the scenario registry: the environment's module
(MuJoCo, the detectors) loads on first make.

Each id carries its time limit twice, in agreement: ``episode_seconds`` for the environment
(40 s joining, 120 s observing; an episode also ends when its scenario does) and
``max_episode_steps`` (400 and 1,200 steps at 10 Hz) for the `gymnasium.wrappers.TimeLimit`
that ``gymnasium.make`` wraps around it, so both truncate on the same step. A longer episode
needs both: ``gymnasium.make(id, episode_seconds=60, max_episode_steps=600)``.

Public surface (loaded on first use): `SocialEnv`, `TruthDetector`, the task (`JoinTask`,
`OSpace`, `estimate_o_space`, `joining_place`, `REWARD_TERMS`), the scripted baseline
(`JoinPolicy`, `evaluate_policy`, `PolicyEvaluation`), `ENV_IDS`.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

import scenarios
from reform._lazy import lazy_exports
from sim.envs.timing import JOIN_EPISODE_S, OBSERVE_EPISODE_S, episode_steps

NAMESPACE = "ReformSim"
ENTRY_POINT = "sim.envs.social:SocialEnv"

# A joining episode needs only the first minute of a party.
_JOIN_OPTIONS: dict[str, dict[str, Any]] = {"party": {"duration": 60.0}}


def _env_name(scenario: str) -> str:
    """``hri-robot-excluded`` -> ``HRIRobotExcluded``."""
    return "".join("HRI" if w == "hri" else w.capitalize() for w in scenario.split("-"))


def _scenes() -> dict[str, tuple[str, dict[str, Any], dict[str, Any]]]:
    """Environment name -> scenario and its options for joining and for observing: every
    scenario with a place for the robot, but those tagged ``randomised``, whose room and crowd
    are drawn anew per seed while an environment's observation space is fixed when it is
    made."""
    out = {}
    for name in scenarios.names():
        info = scenarios.describe(name)
        if info.robot is None or "randomised" in info.tags:
            continue
        join = dict(info.robot)
        for tag in sorted(info.tags & _JOIN_OPTIONS.keys()):
            join |= _JOIN_OPTIONS[tag]
        out[_env_name(name)] = (name, join, dict(info.robot))
    return out


_SCENES = _scenes()
ENV_IDS: tuple[str, ...] = tuple(
    f"{NAMESPACE}/{name}{suffix}-v0" for name in _SCENES for suffix in ("", "Observe")
)


def register_envs() -> None:
    """Registers every environment of `ENV_IDS` (again: registering twice is harmless)."""
    for name, (scenario, join_options, observe_options) in _SCENES.items():
        for suffix, task, options, seconds in (
            ("", "join", join_options, JOIN_EPISODE_S),
            ("Observe", "observe", observe_options, OBSERVE_EPISODE_S),
        ):
            env_id = f"{NAMESPACE}/{name}{suffix}-v0"
            if env_id in gym.registry:
                continue
            gym.register(
                id=env_id,
                entry_point=ENTRY_POINT,
                kwargs={
                    "scenario": scenario,
                    "task": task,
                    "scenario_options": dict(options),
                    "episode_seconds": seconds,
                },
                max_episode_steps=episode_steps(seconds),
                disable_env_checker=False,
            )


register_envs()

_EXPORTS = {
    "SocialEnv": "sim.envs.social",
    "TruthDetector": "sim.envs.social",
    "JoinTask": "sim.envs.reward",
    "OSpace": "sim.envs.reward",
    "REWARD_TERMS": "sim.envs.reward",
    "estimate_o_space": "sim.envs.reward",
    "joining_place": "sim.envs.reward",
    "JoinPolicy": "sim.envs.policy",
    "PolicyEvaluation": "sim.envs.policy",
    "evaluate_policy": "sim.envs.policy",
}

__all__ = sorted([*_EXPORTS, "ENV_IDS", "NAMESPACE", "register_envs"])


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
