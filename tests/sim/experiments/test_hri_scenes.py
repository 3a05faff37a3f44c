"""The paper's HRI experiment runs a fixed, named set of scenes: a scenario written as the
extending guide shows, tagged ``hri``, joins the tag but not the experiment."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import scenarios

PAPER = ("hri-conversation", "hri-robot-excluded", "hri-passing")


def test_a_new_hri_tagged_scenario_leaves_the_papers_three_scenes_alone():
    """In a fresh process, the guide's scenario is registered before the experiments are
    imported (as a package of one's own that registers on import would be)."""
    code = textwrap.dedent(
        """
        import scenarios
        from scenarios.registry import register

        @register("queue", tags=("hri",), robot={})
        def queue(*, seed: int):
            '''People queue in front of the robot.'''
            raise NotImplementedError

        from sim.experiments.calibration import HRI_SCENES
        from sim.experiments.hri import HRI_SCENARIOS

        print("queue" in scenarios.names(tag="hri"), HRI_SCENARIOS, HRI_SCENES)
        """
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert out == f"True {PAPER} {PAPER}"


def test_every_paper_scene_is_registered_and_tagged_hri():
    assert scenarios.PAPER_HRI_SCENES == PAPER
    tagged = scenarios.names(tag="hri")
    assert all(name in tagged for name in scenarios.PAPER_HRI_SCENES)
