"""Start-up time of the ``reform-sim`` command, and the share of short commands' time spent
importing.

Measured in the same run, each a fresh interpreter (median of ``--repeats``), with the
bytecode cache an installed package has (kept in the system's temporary folder, never in the
checkout, whatever ``PYTHONDONTWRITEBYTECODE`` says):

* **python**: ``python -c pass``, the floor under any command;
* **--help**: ``reform-sim --help`` as the console command answers it: the help argparse
  formatted for the parser with each subcommand's name and help line only, kept and read back;
* **data info --help**, **evaluate --help**: one subcommand's arguments added (evaluate's pull
  in the Rerun flags of `sim.recording`, which import neither rerun nor reform's modules);
* **train --help**, **stress --help**: subcommands whose arguments list reform's classifiers
  (`reform.classifiers`, which imports scikit-learn) and the stress tests' grids
  (`sim.experiments.stress_grid`, which imports neither scikit-learn nor MuJoCo);
* **experiment hri --help**: its views and default size come from `sim.experiments.hri_views`
  (light too);
* **import reform**: the package alone, its public names loaded on first use;
* **every parser** (the baseline): gymnasium imported and every subcommand's arguments added, as
  building the parser did before subcommands were added on use.

The ratios --help / python (wall and CPU time) and every parser / --help are medians of the
ratios of runs made one after the other, so that a change of load on the machine hits both
alike.

**Imports' share** of two short commands on the real datasets: ``evaluate --detector gcff
--data salsa`` and ``benchmark`` on salsa, babble, coffeebreak and synth (with its recordings
and figure, into a temporary folder), on every core as by default and with ``--jobs 1``.
Every Python process of the command (its worker processes too) clocks the CPU time of its
imports (each outermost import, whatever it imports in turn); the command's CPU time is that
of its process and the processes it waited for. Printed: the
median share over ``--repeats``, beside the CPU time of ``python -c pass`` in the same run, and
which of the heavy libraries each command imported (a command imports only what it uses:
evaluate without ``--save`` imports no Rerun; benchmark reads the GCFF sets' .mat files without
scipy (`reform.datasets._mat5`) and writes its recordings without pandas, which pyarrow would
import under Rerun; neither imports torch). Goals (issue 31): imports at most 25 % of each
command's CPU time; ``--help`` within 2x of a bare Python start.

Run: ``python benchmarks/bench_cli_startup.py [--repeats 7] [--datasets DIR] [--quick]``
(``--quick``: one run per case, nothing warmed first, and the share of ``scenarios`` only, which
needs no dataset).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from timing import BenchmarkParser

ROOT = Path(__file__).resolve().parents[1]
COMMAND = [sys.executable, "-c", "import sys; from sim.cli import main; sys.exit(main())"]
# The console command, as the ``reform-sim`` script runs it: ``--help`` read back from the help
# kept for this code, Python and terminal (`sim.cli._help_cache`; kept under the benchmark's
# bytecode folder, formatted on the first run, which warming up makes).
CONSOLE = [
    sys.executable,
    "-c",
    "import sys; from sim.cli import console_main; sys.exit(console_main())",
]
EVERY_PARSER = (
    "import argparse, gymnasium\n"
    "from sim.cli import build_parser\n"
    "def build(parser):\n"
    "    for action in parser._actions:\n"
    "        if isinstance(action, argparse._SubParsersAction):\n"
    "            for child in action.choices.values():\n"
    "                child.format_help()\n"
    "                build(child)\n"
    "build(build_parser())\n"
)
CASES = {
    "python": [sys.executable, "-c", "pass"],
    "--help": [*CONSOLE, "--help"],
    "data info --help": [*COMMAND, "data", "info", "--help"],
    "evaluate --help": [*COMMAND, "evaluate", "--help"],
    "train --help": [*COMMAND, "train", "--help"],
    "stress --help": [*COMMAND, "stress", "--help"],
    "experiment hri --help": [*COMMAND, "experiment", "hri", "--help"],
    "import reform": [sys.executable, "-c", "import reform"],
    "every parser": [sys.executable, "-c", EVERY_PARSER],
}
DATASETS = ("salsa", "babble", "coffeebreak", "synth")  # the four datasets at hand
IMPORT_SHARE_GOAL = 0.25  # of a short command's CPU time
HELP_GOAL = 2.0  # --help / python
PYCACHE = "reform-sim-bench-pycache"  # the bytecode cache's folder, in the temporary folder
HEAVY = (
    "rerun",
    "mujoco",
    "torch",
    "sklearn",
    "scipy",
    "pandas",
    "matplotlib",
    "skops",
    "gymnasium",
)

# Installed in every Python process of a measured command (as ``sitecustomize``): clocks the
# CPU time of each outermost import, and writes it with the modules loaded to
# $REFORM_SIM_IMPORT_CLOCK/<pid>.json after each (so a worker ended by a signal has reported).
IMPORT_CLOCK = """\
import importlib._bootstrap as _bootstrap
import json as _json
import os as _os
import sys as _sys
import time as _time

_load = _bootstrap._find_and_load
_state = {"depth": 0, "seconds": 0.0}
_path = _os.path.join(_os.environ["REFORM_SIM_IMPORT_CLOCK"], f"{_os.getpid()}.json")


def _clocked(name, import_):
    if _state["depth"]:
        return _load(name, import_)
    _state["depth"] += 1
    start = _time.process_time()
    try:
        return _load(name, import_)
    finally:
        _state["seconds"] += _time.process_time() - start
        _state["depth"] -= 1
        top = sorted({m.partition(".")[0] for m in list(_sys.modules)})
        with open(_path, "w") as file:
            _json.dump({"imports_s": _state["seconds"], "modules": top}, file)


_bootstrap._find_and_load = _clocked
"""


def _environment(pycache: str, clock: str | None = None) -> dict[str, str]:
    """This process's environment, with the bytecode cache in ``pycache`` and, with ``clock``,
    the import clock installed (its reports written there)."""
    env = dict(os.environ, PYTHONPYCACHEPREFIX=pycache)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if clock is not None:
        env["REFORM_SIM_IMPORT_CLOCK"] = clock
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (str(Path(pycache) / "clock"), env.get("PYTHONPATH")) if p
        )
    return env


def _run(argv: list[str], env: dict[str, str]) -> tuple[float, float]:
    """(wall seconds, CPU seconds of the process and the processes it waited for)."""
    with tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        process = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=err, env=env)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.perf_counter() - start
        process.returncode = os.waitstatus_to_exitcode(status)
        if process.returncode != 0:
            err.seek(0)
            raise SystemExit(
                f"{' '.join(argv[3:]) or argv}: exit status {process.returncode}\n"
                + err.read().decode(errors="replace")
            )
    return wall, usage.ru_utime + usage.ru_stime


def _import_share(argv: list[str], pycache: str) -> tuple[float, float, set[str]]:
    """(import CPU seconds over every process, CPU seconds of the command, heavy libraries
    imported) of one run of ``argv``."""
    with tempfile.TemporaryDirectory() as clock:
        _, cpu = _run(argv, _environment(pycache, clock))
        imports, heavy = 0.0, set()
        for report in Path(clock).glob("*.json"):
            found = json.loads(report.read_text())
            imports += found["imports_s"]
            heavy |= set(found["modules"]) & set(HEAVY)
    return imports, cpu, heavy


def _shares(args, pycache: str) -> None:
    folder = Path(args.datasets)
    found = [name for name in DATASETS if (folder / name).is_dir()]
    if args.quick:
        commands = {"scenarios": ["scenarios"]}
        needed = []
    else:
        commands = {
            "evaluate gcff salsa": ["evaluate", "--detector", "gcff", "--data", "salsa"],
            "benchmark (4 datasets)": ["benchmark", "--quiet"]
            + [w for name in DATASETS for w in ("--data", name)],
        }
        commands["benchmark --jobs 1"] = [*commands["benchmark (4 datasets)"], "--jobs", "1"]
        needed = list(DATASETS)
    if any(name not in found for name in needed):
        print(f"\nimports' share: skipped, {', '.join(needed)} not all in {folder} (--datasets)")
        return
    os.environ["REFORM_SIM_DATASETS"] = str(folder)
    (Path(pycache) / "clock").mkdir(exist_ok=True)
    (Path(pycache) / "clock" / "sitecustomize.py").write_text(IMPORT_CLOCK)
    repeats = 1 if args.quick else max(1, min(args.repeats, 3))
    python = []
    rows = {}
    with tempfile.TemporaryDirectory() as out:
        for name, words in commands.items():
            argv = [*COMMAND, *words]
            if words[0] == "benchmark":
                argv += ["--out", out]
            if not args.quick:
                _import_share(argv, pycache)  # the bytecode cache written, the files cached
            runs = []
            for _ in range(repeats):
                python.append(_run(CASES["python"], _environment(pycache))[1])
                runs.append(_import_share(argv, pycache))
            rows[name] = runs
    print(
        f"\nimports' share of the CPU time (median of {repeats}; python -c pass "
        f"{statistics.median(python):.3f} s CPU in the same run):"
    )
    print(f"{'command':<26} {'imports':>8} {'CPU':>8} {'share':>6}  heavy libraries imported")
    for name, runs in rows.items():
        share = statistics.median(i / c for i, c, _ in runs)
        imports = statistics.median(i for i, _, _ in runs)
        cpu = statistics.median(c for _, c, _ in runs)
        heavy = ", ".join(sorted(set.union(*(h for _, _, h in runs)))) or "none"
        verdict = "met" if share <= IMPORT_SHARE_GOAL else "NOT met"
        print(
            f"{name:<26} {imports:7.2f}s {cpu:7.2f}s {share:6.1%}  {heavy} "
            f"(goal <= {IMPORT_SHARE_GOAL:.0%}: {verdict})"
        )


def main() -> None:
    parser = BenchmarkParser(__doc__, repeats=7)
    parser.add_datasets_argument()
    args = parser.parse_args()
    repeats = args.repeats
    pycache = str(Path(tempfile.gettempdir()) / PYCACHE)
    env = _environment(pycache)
    if not args.quick:
        for argv in CASES.values():  # the bytecode cache written, the file cache warmed
            _run(argv, env)
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in CASES}
    for _ in range(repeats):
        for name, argv in CASES.items():
            times[name].append(_run(argv, env))
    for name, values in times.items():
        walls = [wall for wall, _ in values]
        cpu = statistics.median(c for _, c in values)
        print(
            f"{name:<22} median {statistics.median(walls):6.3f} s  best {min(walls):6.3f} s"
            f"  CPU {cpu:6.3f} s"
        )
    ratios = [e[0] / h[0] for e, h in zip(times["every parser"], times["--help"], strict=True)]
    print(f"every parser / --help: {statistics.median(ratios):.1f}x")
    for clock, k in (("wall", 0), ("CPU", 1)):
        ratio = statistics.median(
            h[k] / p[k] for h, p in zip(times["--help"], times["python"], strict=True)
        )
        verdict = "met" if ratio <= HELP_GOAL else "NOT met"
        print(f"--help / python, {clock}: {ratio:.2f}x (goal <= {HELP_GOAL:g}x: {verdict})")
    _shares(args, pycache)


if __name__ == "__main__":
    main()
