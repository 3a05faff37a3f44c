"""``reform-sim`` starts light: building the parser imports argparse and ``sim.cli`` only, each
subcommand's arguments are added when it is used, and ``import sim`` leaves gymnasium and MuJoCo
unloaded (``import sim.envs`` registers the environments)."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest

from sim.cli import build_parser, main
from sim.cli._common import CommandParser

ROOT = Path(__file__).resolve().parents[3]
# Packages a command needs only once it runs (each costs 0.1 to 0.7 s to import). The package
# `reform` itself is light (its names load on first use); its modules are not, but for the
# detector catalogue, pure Python, which ``--help`` reads to list the detectors and options (with
# the deadlines on a detector's code, the standard library only).
HEAVY = ("gymnasium", "numpy", "scipy", "sklearn", "rerun", "mujoco", "scenarios")
LIGHT = ("reform._lazy", "reform.detectors", "reform.catalogue", "reform.deadline")
LOADED = (
    f"[m for m in sys.modules if m in {HEAVY!r} or m.startswith('reform.') and m not in {LIGHT!r}]"
)


def _python(code: str) -> str:
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    )
    return out.stdout.strip()


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """Every (sub)subcommand's parser by its prog, e.g. ``"reform-sim experiment gcff"``."""
    found = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in dict.fromkeys(action.choices.values()):  # aliases share a parser
                found[child.prog] = child
                child.format_help()  # adds the child's arguments (and its own subcommands)
                found |= _subcommands(child)
    return found


def test_building_the_parser_imports_nothing_heavy() -> None:
    loaded = _python(
        "import sys\n"
        "from sim.cli import build_parser\n"
        "build_parser().format_help()\n"
        f"print({LOADED})\n"
    )
    assert loaded == "[]"


def test_import_reform_is_light_until_a_name_is_used() -> None:
    loaded = _python(f"import sys\nimport reform\nprint({LOADED})\n")
    assert loaded == "[]"
    used = _python("import sys\nimport reform\nreform.Frame\nprint('reform.frame' in sys.modules)")
    assert used == "True"


def test_the_packages_modules_are_attributes_on_first_use() -> None:
    out = _python(
        "import reform, sim\n"
        "print(reform.datasets.read_parquet.__module__, reform.gcff.Gcff is reform.Gcff,\n"
        "      sim.scene.__name__, hasattr(reform, 'no_such_module'))\n"
    )
    assert out == "reform.datasets.parquet True sim.scene False"


@pytest.mark.parametrize(
    "command", ["data info", "evaluate", "detect", "simulate", "stress", "experiment hri", "demo"]
)
def test_a_light_subcommand_imports_nothing_heavy_for_its_help(command: str) -> None:
    loaded = _python(
        "import sys\n"
        "from sim.cli import main\n"
        "try:\n"
        f"    main({command.split()!r} + ['--help'])\n"
        "except SystemExit:\n"
        "    pass\n"
        f"print({LOADED})\n"
    )
    assert loaded.splitlines()[-1] == "[]"


def test_train_help_names_the_classifiers_without_loading_scikit_learn() -> None:
    loaded = _python(
        "import sys\n"
        "from sim.cli import main\n"
        "try:\n"
        "    main(['train', '--help'])\n"
        "except SystemExit:\n"
        "    pass\n"
        "heavy = ('sklearn', 'scipy', 'mujoco')\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in heavy))\n"
    )
    assert loaded.splitlines()[-1] == "[]"


def test_every_subcommand_gets_its_arguments_and_a_handler() -> None:
    parsers = _subcommands(build_parser())
    assert "reform-sim characterize" in parsers
    for name in ("paper", "gcff", "hri", "sim2real"):
        assert f"reform-sim experiment {name}" in parsers
    groups = {"reform-sim data", "reform-sim experiment", "reform-sim policy"}
    for prog, parser in parsers.items():
        assert isinstance(parser, CommandParser)
        if prog not in groups:
            assert callable(parser.get_default("handler")), prog
            assert len(parser._actions) > 1, prog  # more than --help


def test_arguments_are_added_once_whatever_comes_first(capsys) -> None:
    calls = []

    def arguments(parser: argparse.ArgumentParser) -> None:
        calls.append(parser.prog)
        parser.add_argument("--size", type=int, default=1, help="how many")

    top = argparse.ArgumentParser(prog="tool")
    sub = top.add_subparsers(dest="command", required=True, parser_class=CommandParser)
    child = sub.add_parser("go", help="go somewhere", arguments=arguments)
    assert calls == []
    assert "go somewhere" in top.format_help()
    assert calls == []  # the top-level help needs only the help line
    assert "--size SIZE  how many" in child.format_help()
    assert top.parse_args(["go", "--size", "3"]).size == 3
    assert calls == ["tool go"]
    with pytest.raises(SystemExit):
        top.parse_args(["go", "--size", "many"])
    assert "argument --size: invalid int value: 'many'" in capsys.readouterr().err


def test_version_is_the_package_version(capsys) -> None:
    from reform import __version__

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out == f"reform-sim {__version__}\n"


def test_import_sim_loads_neither_gymnasium_nor_mujoco() -> None:
    out = _python(f"import sys\nimport sim\nprint({LOADED})\n")
    assert out == "[]"


def test_import_sim_envs_registers_every_environment() -> None:
    out = _python(
        "import gymnasium\n"
        "before = [i for i in gymnasium.registry if i.startswith('ReformSim/')]\n"
        "import sim.envs\n"
        "after = [i for i in gymnasium.registry if i.startswith('ReformSim/')]\n"
        "print(len(before), after == list(sim.envs.ENV_IDS))\n"
    )
    assert out == "0 True"


def test_gymnasium_make_with_the_module_in_the_id() -> None:
    out = _python(
        "import gymnasium as gym\n"
        "env = gym.make('sim.envs:ReformSim/HRIPassingObserve-v0')\n"
        "print(type(env.unwrapped).__name__, env.spec.id)\n"
    )
    assert out == "SocialEnv ReformSim/HRIPassingObserve-v0"


def test_a_reader_that_leaves_early_is_no_error() -> None:
    """`reform-sim scenarios | head -1`: the pipe closes before the listing is written."""
    process = subprocess.Popen(
        [sys.executable, "-m", "sim.cli", "scenarios"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=Path(__file__).resolve().parents[3],
    )
    process.stdout.close()  # before the command has started: every write finds the pipe gone
    err = process.stderr.read().decode()
    assert process.wait(timeout=60) == 0, err
    assert err == ""


def test_help_loads_no_module_a_bare_start_does_not_need() -> None:
    """``reform-sim --help`` within 2x of a bare Python start (issue 31): its parser needs
    neither `dataclasses` (with `inspect`, a third of its imports) nor `socket`."""
    bare = set(_python("import sys; print(' '.join(sys.modules))").split())
    loaded = _python(
        "import sys\n"
        "from sim.cli import build_parser\n"
        "build_parser().format_help()\n"
        "print(' '.join(sys.modules))\n"
    )
    assert not {"dataclasses", "inspect", "socket"} & (set(loaded.split()) - bare)


# The libraries a run may import only when it uses them: Rerun when it records, skops (which
# imports torch, through scikit-learn's list of estimators) when it reads a model file.
UNUSED = "[m for m in ('rerun', 'skops', 'torch', 'mujoco') if m in sys.modules]"


def test_evaluate_without_a_recording_imports_no_rerun(babble_dir) -> None:
    loaded = _python(
        "import sys\n"
        "from sim.cli import main\n"
        f"main(['evaluate', '--detector', 'gcff', '--data', {str(babble_dir)!r}, '--quiet'])\n"
        f"print({UNUSED})\n"
    )
    assert loaded.splitlines()[-1] == "[]"


def test_evaluate_gcff_imports_no_scikit_learn(babble_dir) -> None:
    """GCFF learns nothing with scikit-learn, so its estimator base is reform's own
    (`reform.estimator`): scikit-learn and what its base imports (scipy.stats, pandas) cost a
    second of CPU that `evaluate --detector gcff` would spend importing (issue 31)."""
    loaded = _python(
        "import sys\n"
        "from sim.cli import main\n"
        f"main(['evaluate', '--detector', 'gcff', '--data', {str(babble_dir)!r}, '--quiet'])\n"
        "print(sorted(m for m in ('sklearn', 'scipy.stats', 'pandas') if m in sys.modules))\n"
    )
    assert loaded.splitlines()[-1] == "[]"


def test_benchmark_without_a_model_imports_no_skops(babble_dir, tmp_path) -> None:
    loaded = _python(
        "import sys\n"
        "from sim.cli import main\n"
        f"main(['benchmark', '--data', {str(babble_dir)!r}, '--detector', 'majority',\n"
        f"      '--no-recordings', '--jobs', '1', '--quiet', '--out', {str(tmp_path)!r}])\n"
        "print([m for m in ('skops', 'torch', 'mujoco') if m in sys.modules])\n"
    )
    assert loaded.splitlines()[-1] == "[]"


def test_generate_without_recordings_imports_no_rerun(tmp_path) -> None:
    loaded = _python(
        "import sys\n"
        "from sim.cli import main\n"
        "main(['generate', '--scenario', 'hri-passing', '--episodes', '1', '--duration', '2',\n"
        f"      '--jobs', '1', '--quiet', '--out', {str(tmp_path / 'data')!r}])\n"
        "print([m for m in ('rerun', 'skops', 'torch') if m in sys.modules])\n"
    )
    assert loaded.splitlines()[-1] == "[]"
