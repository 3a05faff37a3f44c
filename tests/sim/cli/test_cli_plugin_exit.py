"""A plugin detector that calls ``sys.exit(0)`` when its module is imported or in its factory
ends ``detect``, ``evaluate`` and ``benchmark`` with one line naming it and a non-zero status,
never silently with status 0. Each command runs as a user runs it, in a process of its own, the
plugin a ``module:factory`` path in the current folder."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from killed_run import CLI, RUN_TIMEOUT_S
from quiet_generate import generate_quietly

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

PLUGINS = {
    "exit_at_import": "import sys\n\nsys.exit(0)\n\n\ndef make():\n    return None\n",
    "exit_in_factory": "import sys\n\n\ndef make():\n    sys.exit(0)\n",
}
MESSAGES = {
    "exit_at_import": (
        "detector 'exit_at_import:make': cannot import module 'exit_at_import': SystemExit: 0"
    ),
    "exit_in_factory": "detector 'exit_in_factory:make' could not be made: SystemExit: 0",
}


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> Path:
    """A folder holding the plugins and a tiny generated dataset (``ds``)."""
    root = tmp_path_factory.mktemp("plugin-exit")
    for module, source in PLUGINS.items():
        (root / f"{module}.py").write_text(source)
    generate_quietly("hri-conversation", root / "ds", episodes=1, seed=1, duration=5.0)
    return root


@pytest.mark.parametrize("plugin", sorted(PLUGINS))
@pytest.mark.parametrize(
    "command",
    [["detect", "--out", "out.json"], ["evaluate"], ["benchmark", "--out", "bench"]],
    ids=lambda argv: argv[0],
)
def test_a_plugin_that_exits_ends_the_command_in_one_line(lab, command, plugin):
    run = subprocess.run(
        [*CLI, command[0], "--detector", f"{plugin}:make", "--data", "ds", *command[1:]],
        cwd=lab,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
    )
    assert run.returncode == 2
    assert run.stderr == f"reform-sim {command[0]}: error: {MESSAGES[plugin]}\n"
    assert run.stdout == ""
    assert not (lab / "out.json").exists() and not (lab / "bench").exists()
