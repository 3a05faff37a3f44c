"""The folder `reform-sim generate` writes, as the pages show it, against a real small run."""

from __future__ import annotations

import fnmatch
import shlex
from pathlib import Path

import pytest
from quiet_generate import generate_quietly
from site_pages import DOCS, blocks

SCENARIO = "hri-conversation"  # two people and the robot: a cheap scene
EPISODES = 2
DURATION_S = 2.0  # seconds per episode: the layout does not depend on it
# The pages that show a generated folder as lines "DIR/PATH   what it is".
LAYOUT_PAGES = ("guide/synthetic-data.md", "reference/formats.md")
TUTORIAL = "tutorials/synthetic-dataset.md"
WHILE_RUNNING = "only while a run writes"  # a documented entry a finished run has removed


def _files(folder: Path) -> list[str]:
    """Every file under ``folder`` (hidden ones too), relative, sorted."""
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> Path:
    """A folder written by a finished run, recordings included."""
    out = tmp_path_factory.mktemp("layout") / "DIR"
    generate_quietly(
        SCENARIO,
        out,
        episodes=EPISODES,
        seed=1,
        duration=DURATION_S,
        save_recordings=True,
    )
    return out


def _documented(page: str) -> list[tuple[str, str]]:
    """The (path pattern under DIR, description) lines of the page's layout blocks."""
    entries = []
    for block in blocks((DOCS / page).read_text(encoding="utf-8")):
        for line in block.code.splitlines():
            if block.language == "text" and line.startswith("DIR/"):
                path, _, note = line.partition(" ")
                entries.append((path.removeprefix("DIR/"), note.strip()))
    return entries


@pytest.mark.parametrize("page", LAYOUT_PAGES)
def test_every_documented_path_is_where_a_run_writes_it(page, generated):
    documented = _documented(page)
    assert documented, f"{page}: no DIR/... layout block"
    written = _files(generated)
    for path, note in documented:
        for k in range(EPISODES):
            concrete = path.replace("NAME", SCENARIO).replace("=K", f"={k}")
            if note.startswith(WHILE_RUNNING):
                assert concrete not in written, f"{page}: DIR/{path} is left after the run"
            else:
                assert concrete in written, f"{page}: DIR/{path} is not written ({written})"
    patterns = [p.replace("NAME", "*").replace("=K", "=*") for p, _ in documented]
    undocumented = [f for f in written if not any(fnmatch.fnmatch(f, p) for p in patterns)]
    assert not undocumented, f"{page}: a run writes files the page does not show: {undocumented}"


def test_other_tools_read_the_data_folder_as_the_pages_say(generated):
    pd = pytest.importorskip("pandas")
    table = pd.read_parquet(generated / "data")
    assert set(table["scenario"].astype(str)) == {SCENARIO}
    assert sorted(table["episode"].astype(int).unique()) == list(range(EPISODES))
    with pytest.raises(Exception, match="README.md"):  # the folder itself holds the cards
        pd.read_parquet(generated)
    for page in LAYOUT_PAGES:
        assert 'pandas.read_parquet(DIR / "data")' in (DOCS / page).read_text(encoding="utf-8")


def test_the_tutorial_lists_the_files_its_command_writes(tmp_path):
    text = (DOCS / TUTORIAL).read_text(encoding="utf-8")
    page_blocks = blocks(text)
    command = next(b.code for b in page_blocks if "reform-sim generate" in b.code)
    args = shlex.split(command.replace("\\\n", " "))
    scenario = args[args.index("--scenario") + 1]
    episodes = int(args[args.index("--episodes") + 1])
    out = args[args.index("--out") + 1]
    options = dict(args[i + 1].split("=", 1) for i, a in enumerate(args) if a == "--set")
    at = next(i for i, b in enumerate(page_blocks) if b.code.startswith(f"find {out} "))
    listing = page_blocks[at + 1]
    assert listing.language == "text"
    # The page's command but for the episodes' length (the files do not depend on it).
    folder = tmp_path / out
    generate_quietly(
        scenario,
        folder,
        episodes=episodes,
        seed=7,
        duration=DURATION_S,
        options={k: int(v) if v.isdigit() else v for k, v in options.items()},
    )
    assert listing.code.split() == [f"{out}/{f}" for f in _files(folder)]
