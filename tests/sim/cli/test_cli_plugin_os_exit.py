"""A plugin detector that calls ``os._exit(0)`` (which ends a process past every ``except``,
``finally`` and ``atexit``) when its module is imported, in its factory or in ``predict`` ends
``detect``, ``evaluate`` and ``benchmark`` with one line naming it and where it called it, and
status 2, never silently with status 0. Each command runs in a process of its own, the plugin a
``module:factory`` path in the current folder."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest
from killed_run import CLI, RUN_TIMEOUT_S
from quiet_generate import generate_quietly

pytestmark = pytest.mark.faults  # the fault suite: pytest -m faults

PLUGINS = {
    "os_exit_at_import": "import os\n\nos._exit(0)\n\n\ndef make():\n    return None\n",
    "os_exit_in_factory": "import os\n\n\ndef make():\n    os._exit(0)\n",
    "os_exit_in_predict": (
        "import os\n\n\nclass Quitter:\n    def predict(self, frames):\n        os._exit(0)\n\n\n"
        "def make():\n    return Quitter()\n"
    ),
    "os_exit_in_a_thread": (
        "import os, threading, time\n\n\nclass Quitter:\n    def predict(self, frames):\n"
        "        threading.Thread(target=os._exit, args=(0,)).start()\n"
        "        time.sleep(60)\n\n\n"
        "def make():\n    return Quitter()\n"
    ),
}
# What each line says after "reform-sim COMMAND: error: " (a regular expression).
MESSAGES = {
    "os_exit_at_import": (
        r"detector 'os_exit_at_import:make': cannot import module 'os_exit_at_import': "
        r"ProcessExit: os\._exit\(0\) called at \S*os_exit_at_import\.py:3"
    ),
    "os_exit_in_factory": (
        r"detector 'os_exit_in_factory:make' could not be made: "
        r"ProcessExit: os\._exit\(0\) called at \S*os_exit_in_factory\.py:5"
    ),
    "os_exit_in_predict": (
        r"os_exit_in_predict:make: detector raised ProcessExit on frame 0 \(.*\): "
        r"os\._exit\(0\) called at \S*os_exit_in_predict\.py:6"
    ),
    "os_exit_in_a_thread": (
        r"os\._exit\(0\) called at \S*threading\.py:\d+ \(thread .*\) before the command finished"
    ),
}


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> Path:
    """A folder holding the plugins and a tiny generated dataset (``ds``)."""
    root = tmp_path_factory.mktemp("plugin-os-exit")
    for module, source in PLUGINS.items():
        (root / f"{module}.py").write_text(source)
    generate_quietly("hri-conversation", root / "ds", episodes=1, seed=1, duration=5.0)
    return root


def _run(lab: Path, command: list[str], plugin: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [*CLI, command[0], "--detector", f"{plugin}:make", "--data", "ds", *command[1:]],
        cwd=lab,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
    )


@pytest.mark.parametrize(
    "plugin", ["os_exit_at_import", "os_exit_in_factory", "os_exit_in_predict"]
)
@pytest.mark.parametrize(
    "command",
    [["detect", "--out", "out.json"], ["evaluate"], ["benchmark", "--out", "bench", "--quiet"]],
    ids=lambda argv: argv[0],
)
def test_a_plugin_that_calls_os_exit_ends_the_command_in_one_line(lab, command, plugin):
    run = _run(lab, command, plugin)
    assert run.returncode == 2
    assert re.fullmatch(f"reform-sim {command[0]}: error: {MESSAGES[plugin]}\n", run.stderr), (
        run.stderr
    )
    assert run.stdout == ""
    assert not (lab / "out.json").exists() and not (lab / "bench").exists()


def test_os_exit_in_a_thread_of_the_plugin_is_said_in_one_line(lab):
    run = _run(lab, ["detect", "--out", "out.json"], "os_exit_in_a_thread")
    assert run.returncode == 2
    pattern = f"reform-sim detect: error: {MESSAGES['os_exit_in_a_thread']}\n"
    assert re.fullmatch(pattern, run.stderr), run.stderr
    assert not (lab / "out.json").exists()
