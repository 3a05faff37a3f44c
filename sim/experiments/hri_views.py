"""The HRI experiment's views and default size: what `reform-sim experiment hri` can score.

Kept apart from :mod:`sim.experiments.hri` (which builds the views' sensor models and runs the
experiment) so that the command line can list them without loading MuJoCo or scikit-learn.
"""

from __future__ import annotations

__all__ = ["DEFAULT_SEEDS", "VIEW_NAMES"]

# The views, in order (`sim.experiments.hri.VIEWS` holds their sensor models): the ground truth
# of everyone in the room, the robot's head sensor with tracking errors, and the same with a
# wide field of view.
VIEW_NAMES = ("truth", "robot", "robot-wide")
DEFAULT_SEEDS = 10  # episodes per scenario
