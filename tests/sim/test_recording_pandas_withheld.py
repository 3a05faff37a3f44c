"""A command's recordings are written without pandas: pyarrow, which Rerun converts every value
with, would import it (a fifth of a second of CPU) only to find that it is given no pandas object
(issue 31). Each case runs in a fresh interpreter, where pandas is not yet imported."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _python(code: str) -> list[str]:
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    )
    return out.stdout.strip().splitlines()


def test_pandas_cannot_be_imported_within_and_can_after() -> None:
    printed = _python(
        "import sys\n"
        "from sim.recording import pandas_withheld\n"
        "with pandas_withheld():\n"
        "    try:\n"
        "        import pandas\n"
        "    except ModuleNotFoundError as exc:\n"
        "        print(exc)\n"
        "import pandas\n"
        "print(pandas.__name__)\n"
    )
    assert printed == ["pandas is withheld while recordings are written", "pandas"]


def test_pandas_imported_before_stays_usable_within() -> None:
    printed = _python(
        "import pandas\n"
        "from sim.recording import pandas_withheld\n"
        "with pandas_withheld():\n"
        "    import pandas.testing\n"
        "    print(pandas.testing.__name__)\n"
    )
    assert printed == ["pandas.testing"]


def test_arrow_asks_for_pandas_outright_after_a_recording(tmp_path) -> None:
    """pyarrow's explicit pandas functions import pandas as always once the window is over."""
    printed = _python(
        "import numpy as np, pyarrow as pa, sys\n"
        "from sim.recording import pandas_withheld\n"
        "with pandas_withheld():\n"
        "    pa.array(np.arange(3.0)), pa.array([0, 3])\n"
        "print('pandas' in sys.modules)\n"
        "print(pa.table({'a': [1, 2]}).to_pandas()['a'].tolist())\n"
    )
    assert printed == ["False", "[1, 2]"]


def test_benchmark_records_without_importing_pandas(babble_dir, tmp_path) -> None:
    printed = _python(
        "import sys\n"
        "from sim.cli import main\n"
        f"main(['benchmark', '--data', {str(babble_dir)!r}, '--detector', 'majority',\n"
        f"      '--jobs', '1', '--quiet', '--out', {str(tmp_path)!r}])\n"
        "print(sorted(m for m in ('rerun', 'pandas') if m in sys.modules))\n"
    )
    assert printed[-1] == "['rerun']"  # recorded: Rerun is used, pandas is not


def test_evaluate_records_without_importing_pandas(babble_dir, tmp_path) -> None:
    printed = _python(
        "import sys\n"
        "from sim.cli import main\n"
        f"main(['evaluate', '--detector', 'gcff', '--data', {str(babble_dir)!r},\n"
        f"      '--quiet', '--save', {str(tmp_path / 'babble.rrd')!r}])\n"
        "print(sorted(m for m in ('rerun', 'pandas') if m in sys.modules))\n"
    )
    assert printed[-1] == "['rerun']"
