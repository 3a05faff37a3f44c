"""The crowd-shapes table: real datasets and mingle's crowd options side by side."""

from __future__ import annotations

import numpy as np
import pytest

from reform import Frame
from sim.experiments.crowd_shapes import main, nearest_neighbour, real_shapes


def test_nearest_neighbour_of_annotated_frames_only():
    frame = Frame(
        ids=np.array([1, 2, 3]),
        position=np.array([[0.0, 0.0], [0.5, 0.0], [0.5, 2.0]]),
        yaw=np.zeros(3),
        groups=((1, 2), (3,)),
    )
    bare = Frame(ids=frame.ids, position=frame.position, yaw=frame.yaw)
    assert nearest_neighbour([frame, bare]) == pytest.approx([0.5, 0.5, 2.0])


def test_real_rows_measure_salsas_training_split(shared_datasets):
    rows = {row.name: row for row in real_shapes(shared_datasets)}
    assert list(rows) == ["SALSA (train)", "Babble", "CoffeeBreak", "Synth"]
    salsa = rows["SALSA (train)"]
    assert salsa.nn_quantile(0.1) == pytest.approx(0.44, abs=0.01)
    assert salsa.characterisation.mean("symmetry", 5) > 100.0
    assert rows["Babble"].characterisation.mean("symmetry", 5) < 60.0


def test_the_table_prints_a_row_per_simulated_setting(capsys):
    assert main(["--sim-only", "--seeds", "1", "--duration", "20"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("| data | NN q10 m | NN median m | size 2")
    assert [line.split(" | ")[0] for line in lines[2:]] == [
        "| mingle (default)",
        "| mingle spacing=0.46",
        "| mingle spacing=0.46 unevenness=0.75",
        "| mingle spacing=0.46 unevenness=1",
        "| mingle spacing=0.46 arrangements=0.5",
        "| mingle spacing=0.46 furniture=3",
        "| mingle-randomised",
    ]
