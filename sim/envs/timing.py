"""The environments' clocks and time limits, light enough for registration (no MuJoCo).

A registered environment's time limit is given twice on purpose: as ``episode_seconds`` to the
environment, which ends its own episodes there (with its summary and recording), and as
``max_episode_steps`` to Gymnasium's `TimeLimit`, which `gymnasium.make` wraps around it; the
two are the same number of control steps, so both say ``truncated`` on the same step.
"""

from __future__ import annotations

import math

__all__ = [
    "CONTROL_RATE_HZ",
    "DETECT_RATE_HZ",
    "JOIN_EPISODE_S",
    "OBSERVE_EPISODE_S",
    "episode_steps",
]

CONTROL_RATE_HZ = 10.0  # Hz, agent decisions (the world moves at 100 Hz in between)
DETECT_RATE_HZ = 2.0  # Hz, detector runs on the robot's view
JOIN_EPISODE_S = 40.0  # seconds, time limit of a joining episode
OBSERVE_EPISODE_S = 120.0  # seconds, time limit of a registered observing episode


def episode_steps(seconds: float, control_rate: float = CONTROL_RATE_HZ) -> int:
    """Control steps in ``seconds`` at ``control_rate`` Hz (whole steps, at least one)."""
    return max(1, math.floor(seconds / (1.0 / control_rate) + 1e-9))
