"""Every code block of the tutorials runs, in an empty folder, as a reader would run it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from site_pages import DOCS, NEEDS_DATASETS, RUNNABLE_PAGES, blocks, page_script

# Sizes in the tutorials are small: a page runs in well under a minute on two shared cores.
PAGE_TIMEOUT_S = 600
DATASETS_ENV = "REFORM_SIM_DATASETS"
# Recordings a page tells the reader to open, and entities each must hold.
PAGE_RECORDINGS = {"tutorials/gymnasium-loop.md": ("runs/*.rrd", ("people", "groups"))}


def _run_page(text: str, folder: Path, *, datasets: Path | None) -> subprocess.CompletedProcess:
    (folder / "_page.py").write_text(page_script(text))
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["REFORM_SIM_DATA"] = str(folder / "_cache")  # no dataset fetched before the page
    env["MPLBACKEND"] = "Agg"
    env.pop(DATASETS_ENV, None)
    if datasets is not None:
        env[DATASETS_ENV] = str(datasets)
    return subprocess.run(
        [sys.executable, "_page.py"],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
        timeout=PAGE_TIMEOUT_S,
    )


@pytest.mark.slow
@pytest.mark.parametrize("page", RUNNABLE_PAGES)
def test_every_block_of_the_page_runs(page, tmp_path, request):
    text = (DOCS / page).read_text(encoding="utf-8")
    datasets = request.getfixturevalue("shared_datasets") if NEEDS_DATASETS in text else None
    done = _run_page(text, tmp_path, datasets=datasets)
    assert done.returncode == 0, (
        f"{page}: a block failed (exit {done.returncode})\n{done.stderr[-4000:]}"
    )
    ran = done.stderr.count("--- line ")
    assert ran == sum(b.runs for b in blocks(text)) > 0
    if page in PAGE_RECORDINGS:
        pattern, holds = PAGE_RECORDINGS[page]
        recordings = sorted(tmp_path.glob(pattern))
        assert recordings, f"{page}: the blocks wrote no {pattern}"
        for path in recordings:
            entities = _entities(path)
            assert all(any(part in e for e in entities) for part in holds), (path, entities)


def _entities(path: Path) -> set[str]:
    """The entity paths a recording holds, read back from the file."""
    from rerun.chunk import RrdReader

    return {str(chunk.entity_path) for chunk in RrdReader(path).stream().collect().stream()}


@pytest.mark.parametrize("page", RUNNABLE_PAGES)
def test_the_page_has_runnable_blocks_and_marks_the_others(page):
    page_blocks = blocks((DOCS / page).read_text(encoding="utf-8"))
    assert any(b.runs for b in page_blocks), f"{page}: no block runs"
    for block in page_blocks:
        if block.language in ("sh", "shell", "console", "py", "python3"):
            pytest.fail(f"{page}:{block.line}: write ```bash or ```python, not ```{block.language}")


SAMPLE = """\
# A page

```bash
echo one > one.txt
```

```python title="pkg/mod.py"
VALUE = 3
```

<!-- not run: opens a window -->
```bash
exit 1
```

```python
from pkg.mod import VALUE
assert VALUE == 3
seen = open("one.txt").read().strip()
```

```text
shown only
```

```python
assert seen == "one"
```
"""


def test_the_runner_writes_files_skips_marked_blocks_and_shares_python_names(tmp_path):
    found = blocks(SAMPLE)
    assert [(b.language, b.title, b.skipped, b.runs) for b in found] == [
        ("bash", None, False, True),
        ("python", "pkg/mod.py", False, False),
        ("bash", None, True, False),
        ("python", None, False, True),
        ("text", None, False, False),
        ("python", None, False, True),
    ]
    done = _run_page(SAMPLE, tmp_path, datasets=None)
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("--- line ") == 3


def test_a_failing_block_fails_the_page_and_names_its_line(tmp_path):
    page = "# A page\n\n```bash\ntrue\n```\n\n```python\nraise SystemExit('broken')\n```\n"
    done = _run_page(page, tmp_path, datasets=None)
    assert done.returncode != 0
    assert "--- line 7: python" in done.stderr
    assert "broken" in done.stderr


# The pages a newcomer reads first: each says how to run its commands before the first one.
SHELL_NOTE = "source .venv/bin/activate"
NEWCOMER_PAGES = (*RUNNABLE_PAGES, "guide/demo.md")


def _command_lines(text: str) -> list[int]:
    """The lines (1-based) of the page's ``reform-sim`` and ``rerun`` commands: in code blocks,
    or inline (```reform-sim ...```)."""
    lines = [
        block.line + k
        for block in blocks(text)
        for k, code in enumerate(block.code.splitlines(), start=1)
        if code.lstrip().startswith(("reform-sim ", "rerun "))
    ]
    lines += [
        n
        for n, line in enumerate(text.splitlines(), start=1)
        if "`reform-sim " in line or "`rerun " in line
    ]
    return sorted(lines)


@pytest.mark.parametrize("page", NEWCOMER_PAGES)
def test_the_page_says_how_to_run_its_commands_near_the_top(page):
    text = (DOCS / page).read_text(encoding="utf-8")
    lines = text.splitlines()
    assert _command_lines(text), f"{page}: no reform-sim or rerun command"
    # Near the top: in the introduction, before the first section and the first code block.
    first_section = next((n for n, line in enumerate(lines) if line.startswith("## ")), len(lines))
    first_block = min((b.line - 1 for b in blocks(text)), default=len(lines))
    intro = "\n".join(lines[: min(first_section, first_block)])
    assert SHELL_NOTE in intro, f"{page}: does not say {SHELL_NOTE!r} in its introduction"


def test_the_figure_of_the_field_s_words_is_the_script_s(tmp_path):
    import importlib.util

    from matplotlib.image import imread

    spec = importlib.util.spec_from_file_location("figures", DOCS / "figures.py")
    figures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(figures)
    drawn = imread(figures.draw(tmp_path / "f-formation.png"))
    shipped = imread(figures.IMAGE)
    assert drawn.shape == shipped.shape and drawn.shape[2] in (3, 4)
    assert f"images/{figures.IMAGE.name}" in (DOCS / "getting-started.md").read_text()
    # The table's answers are reform.evaluate's: {1, 2} finds {1, 2, 3} at T = 2/3, not at T = 1.
    assert figures._scores() == [
        ("{1, 2} and {3}", "yes", "no"),
        ("{1, 2, 3, 4}", "yes", "no"),
        ("{1, 2, 3, 4, 5}", "no", "no"),
    ]
