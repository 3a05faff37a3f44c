"""docs/gymnasium.md: every Python example on the page runs, and prints what it says."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

PAGE = Path(__file__).resolve().parents[2] / "docs" / "gymnasium.md"
BLOCKS = re.findall(r"```python\n(.*?)```", PAGE.read_text(), flags=re.S)


def test_the_page_has_its_examples() -> None:
    assert len(BLOCKS) == 5


@pytest.mark.parametrize("index", range(len(BLOCKS)), ids=lambda k: f"example-{k + 1}")
def test_example_runs(index: int, tmp_path: Path) -> None:
    code = BLOCKS[index]
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr[-2000:]
    # Each "# value" comment after a print is what the print shows.
    for line in code.splitlines():
        match = re.match(r"\s*print\(.*\)\s*# (.+)$", line)
        if match:
            assert match.group(1).split(":")[0] in out.stdout, (line, out.stdout)
    if "mingle.png" in code:
        assert (tmp_path / "mingle.png").read_bytes()[:4] == b"\x89PNG"
