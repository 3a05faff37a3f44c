"""Running ``reform-sim`` in a test: its status and output, or its one-line error."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from sim.cli import main


def run_cli(argv: list[Any], capsys: Any) -> tuple[int, str, str]:
    """Runs ``reform-sim argv`` (each item made a string): its exit status, stdout and stderr."""
    status = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def cli_json(argv: list[Any], path: Path, capsys: Any) -> tuple[Any, str, str]:
    """Runs ``reform-sim argv`` to success (exit status 0) and reads the JSON file ``path`` it
    wrote: the JSON document, stdout and stderr."""
    status, out, err = run_cli(argv, capsys)
    assert status == 0, err
    return json.loads(path.read_text()), out, err


def cli_error(argv: list[Any], capsys: Any) -> str:
    """Runs ``reform-sim argv`` (each item made a string), asserts exit status 2 and a single
    line on stderr, and returns that line."""
    status, _, err = run_cli(argv, capsys)
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1, err
    return err.strip()


# Runs a command from a small launcher process and reports the command's own peak memory: a
# child forked from the test process would count the test process's pages in its peak.
_LAUNCHER = """
import json, os, subprocess, sys
child = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
err = child.stderr.read()
_, status, usage = os.wait4(child.pid, 0)
child.stderr.close()
print(json.dumps({"status": os.waitstatus_to_exitcode(status), "peak": usage.ru_maxrss * 1024,
                  "stderr": err.decode("utf-8", "replace")}))
"""


def cli_peak(argv: list[Any]) -> tuple[int, str, int]:
    """Runs ``python -m sim.cli argv`` in a fresh process: its exit status, its stderr and its
    peak resident memory in bytes (Linux)."""
    import json
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-c", _LAUNCHER, sys.executable, "-m", "sim.cli", *map(str, argv)],
        capture_output=True,
        text=True,
        check=True,
    )
    result = json.loads(out.stdout)
    return result["status"], result["stderr"], result["peak"]
