"""A researcher's detector from outside the package: a small plugin package, installed by pip
into a folder of its own with its ``reform_sim.detectors`` entry points, run by ``reform-sim
evaluate`` and ``reform-sim stress`` as a user would, in subprocesses; also by its
``module:factory`` path without installing it, and broken plugins giving one line."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from reform import Dataset, Frame, write_parquet

REFORM_SIM = Path(sys.executable).with_name("reform-sim")  # the console command of this venv
CLOSE_M = 1.0  # the plugin's rule: people closer than this are in one group

PLUGIN = '''
"""A lab's detector: people closer than 1 m to each other are in one group (chained)."""

import numpy as np

CLOSE_M = 1.0  # metres


class Pairs:
    def fit(self, frames):
        self.frames_seen_ = len(frames)
        return self

    def predict(self, frames):
        partitions = []
        for frame in frames:
            ids = [int(i) for i in frame.ids]
            label = list(range(len(ids)))
            gaps = np.linalg.norm(frame.position[:, None] - frame.position[None], axis=-1)
            for a, b in zip(*np.nonzero(np.triu(gaps < CLOSE_M, 1))):
                old, new = label[b], label[a]
                label = [new if x == old else x for x in label]
            groups = {}
            for person, x in zip(ids, label):
                groups.setdefault(x, []).append(person)
            partitions.append([tuple(g) for g in groups.values()])
        return partitions


def make():
    return Pairs()


class Raises(Pairs):
    def predict(self, frames):
        if any(frame.time >= 2 for frame in frames):
            raise RuntimeError("the lab's model file is missing")
        return super().predict(frames)


class Forgets(Pairs):
    def predict(self, frames):
        return [partition[1:] for partition in super().predict(frames)]
'''

PYPROJECT = """
[build-system]
requires = []
build-backend = "backend"
backend-path = ["."]

[project]
name = "myplugin"
version = "0.1"

[project.entry-points."reform_sim.detectors"]
pairs = "myplugin:make"
pairs-raises = "myplugin:Raises"
pairs-forgets = "myplugin:Forgets"
"""

# setuptools as a fresh venv has it cannot build wheels (no `wheel` package), so the plugin
# carries the smallest PEP 517 backend that builds its one module and its entry points.
BACKEND = """
import base64, hashlib, tomllib, zipfile
from pathlib import Path


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    project = tomllib.loads(Path("pyproject.toml").read_text())["project"]
    name, version = project["name"], project["version"]
    info = f"{name}-{version}.dist-info"
    entry_points = "".join(
        f"[{group}]\\n" + "".join(f"{key} = {value}\\n" for key, value in points.items())
        for group, points in project["entry-points"].items()
    )
    files = {
        f"{name}.py": Path(f"{name}.py").read_bytes(),
        f"{info}/METADATA": f"Metadata-Version: 2.1\\nName: {name}\\nVersion: {version}\\n"
        .encode(),
        f"{info}/WHEEL": b"Wheel-Version: 1.0\\nGenerator: test\\nRoot-Is-Purelib: true\\n"
        b"Tag: py3-none-any\\n",
        f"{info}/entry_points.txt": entry_points.encode(),
    }
    record = ""
    for path, data in files.items():
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        record += f"{path},sha256={digest},{len(data)}\\n"
    wheel = f"{name}-{version}-py3-none-any.whl"
    with zipfile.ZipFile(Path(wheel_directory) / wheel, "w") as archive:
        for path, data in files.items():
            archive.writestr(path, data)
        archive.writestr(f"{info}/RECORD", record + f"{info}/RECORD,,\\n")
    return wheel
"""


def ring(centre: tuple[float, float], size: int) -> tuple[np.ndarray, np.ndarray]:
    """``size`` people 0.4 m from ``centre`` facing it (neighbours well within 1 m)."""
    angles = np.arange(size) * 2 * np.pi / size
    position = np.asarray(centre) + 0.4 * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    yaw = (angles + 2 * np.pi) % (2 * np.pi) - np.pi
    return position, yaw


def scene(t: int) -> Frame:
    """Groups of 2, 3 and 4 and two people alone, 5 m apart; each frame shifted a little."""
    positions, yaws, groups, person = [], [], [], 1
    for k, size in enumerate((2, 3, 4)):
        position, yaw = ring((5.0 * k + 0.1 * t, 0.0), size)
        positions.append(position)
        yaws.append(yaw)
        groups.append(tuple(range(person, person + size)))
        person += size
    positions.append(np.array([[0.0, 5.0], [10.0, 5.0]]))
    yaws.append(np.zeros(2))
    return Frame(
        ids=np.arange(1, person + 2),
        position=np.concatenate(positions),
        yaw=np.concatenate(yaws),
        groups=tuple(groups),
        time=float(t),
        sequence="lab",
    )


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> dict[str, Path]:
    """The plugin's source folder, the folder pip installed it into, and a small dataset."""
    root = tmp_path_factory.mktemp("lab")
    source = root / "myplugin"
    source.mkdir()
    (source / "myplugin.py").write_text(PLUGIN)
    (source / "pyproject.toml").write_text(PYPROJECT)
    (source / "backend.py").write_text(BACKEND)
    site = root / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-index"]
        + ["--no-build-isolation", "--target", str(site), str(source)],
        check=True,
        capture_output=True,
        text=True,
    )
    data = root / "lab.parquet"
    write_parquet(Dataset(frames=tuple(scene(t) for t in range(4)), name="lab"), data)
    return {"source": source, "site": site, "data": data, "root": root}


def reform_sim(*args, lab, installed: bool = True, cwd: Path | None = None):
    """``reform-sim args`` in a subprocess, the plugin on the path when ``installed``."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if installed:
        env["PYTHONPATH"] = str(lab["site"])
    return subprocess.run(
        [str(REFORM_SIM), *map(str, args)],
        capture_output=True,
        text=True,
        env=env,
        cwd=cwd or lab["root"],
        timeout=300,
    )


def test_pip_installed_the_plugin_with_its_entry_points(lab):
    (info,) = lab["site"].glob("myplugin-0.1.dist-info")
    assert "pairs = myplugin:make" in (info / "entry_points.txt").read_text()
    assert (info / "INSTALLER").read_text().strip() == "pip"


@pytest.mark.slow
def test_evaluate_an_installed_plugin_by_name(lab):
    out = lab["root"] / "pairs.json"
    run = reform_sim(
        "evaluate", "--detector", "pairs", "--data", lab["data"], "--json", out, lab=lab
    )
    assert run.returncode == 0, run.stderr
    assert "lab" in run.stdout and "F1" in run.stdout
    result = json.loads(out.read_text())
    assert (result["detector"], result["dataset"], result["frames"]) == ("pairs", "lab", 4)
    # Every group's neighbours are 0.4-0.8 m apart and groups 5 m apart: all found exactly.
    assert result["1"]["f1"] == 1.0 and result["pairwise_accuracy"] == 1.0


@pytest.mark.slow
def test_evaluate_a_plugin_by_its_path_without_installing_it(lab):
    def evaluate_from(cwd):
        return reform_sim(
            "evaluate",
            "--detector",
            "myplugin:make",
            "--data",
            lab["data"],
            lab=lab,
            installed=False,
            cwd=cwd,
        )

    run = evaluate_from(lab["source"])
    assert run.returncode == 0, run.stderr
    assert "myplugin:make" in run.stdout
    elsewhere = lab["root"] / "elsewhere"
    elsewhere.mkdir()
    not_here = evaluate_from(elsewhere)
    assert not_here.returncode == 2
    assert not_here.stderr == (
        "reform-sim evaluate: error: detector 'myplugin:make': cannot import module 'myplugin': "
        "ModuleNotFoundError: No module named 'myplugin' (is the package installed, or its folder "
        "on PYTHONPATH?)\n"
    )


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "message"),
    [
        (
            "pairs-raises",
            "pairs-raises: detector raised RuntimeError on frame 2 (lab t=2 s): the lab's model "
            "file is missing",
        ),
        (
            "pairs-forgets",
            "pairs-forgets: detector output for frame 0 (lab t=0 s): person 1 is in no group; a "
            "prediction must be a full partition of the frame's ids, singletons included",
        ),
    ],
    ids=["raises", "not-a-partition"],
)
def test_a_broken_plugin_is_one_line_naming_it_and_the_frame(lab, name, message):
    run = reform_sim("evaluate", "--detector", name, "--data", lab["data"], lab=lab)
    assert (run.returncode, run.stdout) == (2, "")
    assert run.stderr == f"reform-sim evaluate: error: {message}\n"  # one line, no traceback


STRESS = ("stress", "--grid", "small", "--axes", "position-noise", "--episodes", "2", "--jobs", "2")


@pytest.mark.slow
def test_stress_runs_an_installed_plugin_beside_the_built_ins(lab):
    out = lab["root"] / "stress"
    run = reform_sim(*STRESS, "--detector", "pairs", "--out", out, lab=lab)
    assert run.returncode == 0, run.stderr
    assert f"wrote json: {out / 'stress.json'}" in run.stdout
    assert "fitting pairs on" in run.stderr
    result = json.loads((out / "stress.json").read_text())
    assert list(result["detectors"])[-1] == "pairs"
    assert "--detector pairs" in result["command"]
    (axis,) = result["axes"]
    scores = [point["scores"]["pairs"]["2/3"]["f1"] for point in axis["points"]]
    assert len(scores) == 3 and all(
        0.0 <= s["low"] <= s["value"] <= s["high"] <= 1.0 for s in scores
    )
    assert scores[0]["value"] > scores[-1]["value"]  # 0.5 m of noise hurts it too
    assert result["training"]["plugins"]["pairs"].startswith("fitted on the ")
    assert all(
        math.isfinite(p["scores"]["gcff-tuned"]["2/3"]["f1"]["value"]) for p in axis["points"]
    )


@pytest.mark.slow
def test_stress_stops_on_a_broken_plugin_in_one_line(lab):
    run = reform_sim(*STRESS, "--detector", "pairs-raises", "--out", lab["root"] / "s2", lab=lab)
    assert run.returncode == 2
    last = run.stderr.splitlines()[-1]
    assert last.startswith("reform-sim stress: error: pairs-raises: detector raised RuntimeError ")
    assert last.endswith(": the lab's model file is missing")
    assert "Traceback" not in run.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--detector", "gcff-tuned"],
            "--detector gcff-tuned: stress always runs GCFF (trained on its ",
        ),
        (["--detector", "pairs", "--detector", "pairs"], "--detector pairs is given twice"),
        (["--detector", "myplugin:nothing"], "detector 'myplugin:nothing': module 'myplugin' has "),
    ],
    ids=["built-in", "twice", "no-attribute"],
)
def test_stress_checks_its_detectors_before_running(lab, args, message):
    run = reform_sim("stress", "--grid", "small", *args, "--out", lab["root"] / "s3", lab=lab)
    assert (run.returncode, run.stdout) == (2, "")
    assert run.stderr.startswith(f"reform-sim stress: error: {message}")
    assert len(run.stderr.splitlines()) == 1
    assert not (lab["root"] / "s3").exists()


def test_the_plugins_rule_is_what_the_test_data_assume():
    frame = scene(0)
    gaps = np.linalg.norm(frame.position[:, None] - frame.position[None], axis=-1)
    together = np.zeros_like(gaps, dtype=bool)
    for group in frame.groups:
        rows = np.isin(frame.ids, group)
        together |= rows[:, None] & rows[None]
    np.fill_diagonal(together, False)
    assert gaps[together].max() < CLOSE_M < gaps[~together & ~np.eye(len(gaps), dtype=bool)].min()
    assert f"CLOSE_M = {CLOSE_M}  # metres" in PLUGIN


def test_run_stress_keeps_the_built_in_names_for_the_built_ins():
    from reform import Majority
    from sim.experiments.stress import run_stress

    with pytest.raises(ValueError, match=r"^plugins must be named apart from the built-in"):
        run_stress("small", plugins={"gcff-tuned": Majority()})


@pytest.mark.slow
def test_benchmark_runs_an_installed_plugin_beside_the_built_ins(lab):
    out = lab["root"] / "benchmark"
    run = reform_sim(
        "benchmark",
        "--data",
        lab["data"],
        "--detector",
        "pairs",
        "--detector",
        "gcff",
        "--out",
        out,
        "--quiet",
        lab=lab,
    )
    assert run.returncode == 0, run.stderr
    data = json.loads((out / "benchmark.json").read_text())
    (cell,) = [c for c in data["cells"] if c["detector"] == "pairs"]
    assert cell["dataset"] == "lab.parquet" and cell["scores"]["T=1"]["f1"] == 1.0
    assert (out / "recordings" / "lab-parquet.rrd").is_file()


def test_benchmark_stops_on_a_broken_plugin_in_one_line(lab):
    run = reform_sim(
        "benchmark",
        "--data",
        lab["data"],
        "--detector",
        "pairs-raises",
        "--out",
        lab["root"] / "b2",
        "--quiet",
        lab=lab,
    )
    assert run.returncode == 2
    assert run.stderr.startswith("reform-sim benchmark: error: pairs-raises: detector raised ")
    assert run.stderr.count("\n") == 1 and "Traceback" not in run.stderr
