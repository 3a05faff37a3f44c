"""Progress bars: tqdm's when shown; a disabled one draws nothing and leaves tqdm unimported."""

from __future__ import annotations

import io
import subprocess
import sys

from sim.progress import progress_bar
from sim.ticking import ticking


def test_a_disabled_bar_counts_draws_nothing_and_imports_no_tqdm() -> None:
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys\n"
            "from sim.progress import progress_bar\n"
            "from sim.ticking import ticking\n"
            "with progress_bar(total=3, desc='x', disable=True) as bar, ticking(bar):\n"
            "    bar.update(2)\n"
            "    bar.set_postfix_str('y', refresh=False)\n"
            "    bar.refresh()\n"
            "print(bar.n, bar.total, 'tqdm' in sys.modules)\n",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    assert (out.stdout, out.stderr) == ("2 3 False\n", "")


def test_a_shown_bar_is_tqdms() -> None:
    from tqdm import tqdm

    stream = io.StringIO()
    with progress_bar(total=2, desc="cells", file=stream) as bar, ticking(bar):
        bar.update(2)
    assert isinstance(bar, tqdm)
    assert "cells: 100%" in stream.getvalue()
