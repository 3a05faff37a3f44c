"""The speed benchmarks cannot rot: each runs its ``--quick`` smoke run, and imports only the
project's public names.

A quick run uses tiny sizes and one or two repeats; it must exit 0 (every equality check of the
full run still holds: fast path against baseline) and print its figure lines. No timing is
asserted: speed is read from the full runs (``make bench``), never from tests.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
BENCHMARKS_DIR = REPO_ROOT / "benchmarks"
BENCHMARKS = sorted(BENCHMARKS_DIR.glob("bench_*.py"))
QUICK_TIMEOUT_S = 120  # seconds for one quick run (they take 1-15 s on a busy 2-core machine)


def _timing_module():
    """``benchmarks/timing.py``, the scripts' shared helpers (not a package: loaded by path)."""
    spec = importlib.util.spec_from_file_location("benchmarks_timing", BENCHMARKS_DIR / "timing.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


DATASETS_MISSING = _timing_module().DATASETS_MISSING

# What each benchmark's quick run must print: its figure lines, each a pattern matched against
# one line of its output. A new benchmark needs an entry here.
FIGURES: dict[str, tuple[str, ...]] = {
    "bench_backends": (
        r"^stress \(.*\) +local \d+ processes +[\d.]+ s +ray +[\d.]+ s +ray / local: [\d.]+x$",
        r"^generate \(.*\) +local \d+ processes +[\d.]+ s +ray +[\d.]+ s +ray / local: [\d.]+x$",
    ),
    "bench_characterisation": (
        r"^characterise +[\d.]+ ms +per-item loop +[\d.]+ ms +ratio +[\d.]+x$",
        r"^pair_feature_samples +[\d.]+ ms +per-item loop +[\d.]+ ms +ratio +[\d.]+x$",
    ),
    "bench_cli_startup": (
        r"^--help +median +[\d.]+ s +best +[\d.]+ s +CPU +[\d.]+ s$",
        r"^every parser / --help: [\d.]+x$",
        r"^--help / python, CPU: [\d.]+x \(goal <= 2x: (met|NOT met)\)$",
        r"^scenarios +[\d.]+s +[\d.]+s +[\d.]+% ",
    ),
    "bench_concourse": (
        r"^bare mj_kinematics +[\d.]+x real time$",
        r"^rollout +[\d.]+x real time +rollout / bare: [\d.]+x$",
        r"^Target: the rollout at >= 10x real time at 1,000 people: [\d.]+x at 150 \(",
    ),
    "bench_crowd": (
        r"^ +400 +[\d.]+ +[\d.]+ +[\d.]+x +[\d.]+ +[\d.]+ +- +[\d.]+  same$",
        r"^growth from 200 to 400 people: REFORM time n\^-?[\d.]+, memory n\^-?[\d.]+; GCFF ",
        r"^Targets: .*peak [\d.]+ MB \(< 500: met\)",
    ),
    "bench_dante": tuple(rf"^ +{n} +[\d.]+ ms +[\d.]+ ms +[\d.]+x$" for n in (6, 18)),
    "bench_envs": (
        r"^ +7 ReformSim/WordImprov-v0 .* [\d.]+x +\d+$",
        r"^ +18 ReformSim/Mingle-v0 .* [\d.]+x +\d+$",
        r"^target: >= 2,000 env steps/s with 7 people: (met|NOT met) ",
    ),
    "bench_field_detectors": tuple(
        rf"^ +{name} +{n} +[\d.]+ ms +[\d.]+ ms +[\d.]+x$"
        for name in ("proximity", "dominant-sets", "gtcg", "hvff", "hvff-multiscale")
        for n in (6, 18, 200)
    ),
    "bench_gcff": tuple(rf"^ +{n} +[\d.]+ ms +[\d.]+ ms +[\d.]+x +\d+$" for n in (6, 18, 50, 200)),
    "bench_generate": (
        r"^ +total +\d+ us +\([\d,]+ frames per CPU second\)$",
        r"^serial +[\d,]+ +[\d,]+ +[\d.]+$",
        r"^2 processes / serial, wall clock: [\d.]+x$",
        r"^one million annotated frames: [\d.]+ min ",
    ),
    "bench_loaders": tuple(
        rf"^{task} +[\d.]+ +[\d.]+ +[\d.]+x$"
        for task in ("SALSA load_salsa", "Babble load_babble", "SALSA read_parquet")
    ),
    "bench_metrics": (
        r"^evaluate, \d+ SALSA frames, .*: [\d.]+ ms .* loop baseline [\d.]+ ms; ratio [\d.]+x ",
    ),
    "bench_recording": (
        r"^  simulate_episode \(truth view\) +[\d.]+ s +baseline$",
        r"^  record_episode: truth \+ events \(simulate --save\) +[\d.]+ s +ratio [\d.]+ ",
        r"^The goal is (met|NOT met) at 2 Hz\.$",
    ),
    "bench_reform": (
        *(rf"^{name} +18 +[\d.]+ +[\d.]+ +[\d.]+ " for name in ("weighted-knn", "bagged-trees")),
        r"^Targets, Bagged Trees, 18 people: .* predictions identical: yes$",
        r"^  reconstruction='correlation' +30 people: +[\d.]+ ms/frame, +[\d.]+x the defaults' ",
    ),
    "bench_resume": (
        *(
            rf"^{where} +[\d.]+ s +[\d.]+ s +[\d.]+ s +[\d.]+%$"
            for where in ("local disk", "S3 server")
        ),
        r"^target: checks on resume <= 10% of the generation: (met|NOT met) \([\d.]+%\)$",
    ),
    "bench_sim": (
        r"^ +18 +[\d,]+x +[\d,]+x +[\d.]+ +[\d,]+x +[\d.]+ ",
        r"^18 people: [\d,]+x real time ",
    ),
    "bench_store": (
        r"^local disk +[\d,]+ frames/s ",
        r"^S3 server +[\d,]+ frames/s ",
        r"^store / disk ratio [\d.]+x$",
        r"^per shard: [\d.]+ s .* KiB, 2\.0 PUT requests, \d+ bytes of card$",
        r"^paper: 64 workers x 1,000,000 episodes: [\d.]+ h, .* requests/s to the store ",
    ),
    "bench_temporal": (
        r"^evaluate_events \+JSON +[\d.]+ ms +evaluate \(frame P/R/F1\) \+JSON +[\d.]+ ms "
        r"+ratio [\d.]+x ",
        r"^goal: temporal metrics under 1 s: (met|NOT met) ",
    ),
    "bench_twin": (
        r"^load SALSA \(baseline\) +[\d.]+ +1\.0$",
        r"^twin fitted and generated: [\d.]+ s \(goal < 60 s: (met|NOT met)\)$",
    ),
    "bench_stress": (
        r"^  reform\.evaluate \(baseline\) +[\d.]+ s +1\.0 x baseline$",
        r"^  predict: bagged-trees +[\d.]+ s +[\d.]+ x baseline$",
        r"^run_stress\('quick', jobs=1\): [\d.]+ s wall, [\d.]+ s CPU, \d+ frames scored ",
    ),
}


@pytest.mark.slow
@pytest.mark.parametrize("script", BENCHMARKS, ids=lambda path: path.stem)
def test_quick_run_passes_its_checks_and_prints_its_figures(
    script: Path, request: pytest.FixtureRequest
) -> None:
    assert script.stem in FIGURES, f"{script.name}: add the figure lines it prints to FIGURES"
    run = subprocess.run(
        [sys.executable, str(script.relative_to(REPO_ROOT)), "--quick"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=QUICK_TIMEOUT_S,
        check=False,
    )
    if run.returncode == DATASETS_MISSING:
        request.getfixturevalue("shared_datasets")  # skips, or fails under CI, when missing
        pytest.fail(f"{script.name} did not find the datasets the tests found: {run.stderr}")
    assert run.returncode == 0, f"{script.name} --quick failed:\n{run.stdout}\n{run.stderr}"
    lines = run.stdout.splitlines()
    missing = [p for p in FIGURES[script.stem] if not any(re.search(p, line) for line in lines)]
    assert not missing, f"{script.name} --quick printed no line matching {missing}:\n{run.stdout}"


@pytest.mark.slow
def test_choose_field_defaults_quick_run_prints_a_choice_per_detector(
    request: pytest.FixtureRequest,
) -> None:
    # benchmarks/choose_field_defaults.py chooses the field detectors' defaults on SALSA's
    # training split; its quick run must print one table row per detector it chooses for.
    script = BENCHMARKS_DIR / "choose_field_defaults.py"
    run = subprocess.run(
        [sys.executable, str(script.relative_to(REPO_ROOT)), "--quick"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=QUICK_TIMEOUT_S,
        check=False,
    )
    if run.returncode == DATASETS_MISSING:
        request.getfixturevalue("shared_datasets")  # skips, or fails under CI, when missing
        pytest.fail(f"{script.name} did not find the datasets the tests found: {run.stderr}")
    assert run.returncode == 0, f"{script.name} --quick failed:\n{run.stdout}\n{run.stderr}"
    assert re.search(
        r"^SALSA training split .*: \d+ frames, every 120th scored: \d+ frames", run.stdout, re.M
    )
    for name in ("proximity", "dominant-sets", "gtcg", "hvff", "hvff-multiscale"):
        row = rf"^\| {name} \| [a-z_]+=[\d.]+.* \| [\d.]+ \| .* \| \d+ \|$"
        assert re.search(row, run.stdout, re.M), f"no row for {name}:\n{run.stdout}"


def _project_packages() -> set[str]:
    """Top-level packages found inside the repository (not installed from elsewhere)."""
    found = set()
    for path in REPO_ROOT.iterdir():
        if (path / "__init__.py").is_file():
            spec = importlib.util.find_spec(path.name)
            if spec is not None and spec.origin and Path(spec.origin).is_relative_to(REPO_ROOT):
                found.add(path.name)
    return found


def _is_submodule(module: object, name: str) -> bool:
    return hasattr(module, "__path__") and (
        importlib.util.find_spec(f"{module.__name__}.{name}") is not None
    )


def _private_uses(source: str, project: set[str]) -> list[str]:
    """The project's private names a script uses: underscored modules or names, names outside a
    module's ``__all__``, and underscored attributes of anything but ``self``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            parts = node.module.split(".")
            if parts[0] not in project:
                continue
            if any(part.startswith("_") for part in parts):
                found.append(f"line {node.lineno}: module {node.module}")
                continue
            module = importlib.import_module(node.module)
            exported = getattr(module, "__all__", None)
            for alias in node.names:
                if alias.name.startswith("_") or (
                    exported is not None
                    and alias.name not in exported
                    and not _is_submodule(module, alias.name)
                ):
                    found.append(f"line {node.lineno}: {node.module}.{alias.name}")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] in project and any(part.startswith("_") for part in parts):
                    found.append(f"line {node.lineno}: module {alias.name}")
        elif (
            isinstance(node, ast.Attribute)
            and node.attr.startswith("_")
            and not node.attr.startswith("__")
            and not (isinstance(node.value, ast.Name) and node.value.id == "self")
        ):
            found.append(f"line {node.lineno}: attribute .{node.attr}")
    return found


@pytest.mark.parametrize("script", sorted(BENCHMARKS_DIR.glob("*.py")), ids=lambda path: path.stem)
def test_imports_only_public_names(script: Path) -> None:
    private = _private_uses(script.read_text(), _project_packages())
    assert not private, f"{script.name} uses private names of the project: {private}"
