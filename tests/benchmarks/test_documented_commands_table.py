"""``benchmarks/documented_commands.py --update`` keeps the rows of the pages it does not run: its
table reads back as written, an earlier table without a commit column reads with the commit its
first paragraph names, and a run of one page replaces that page's rows alone."""

from __future__ import annotations

import pytest

# The earlier form of the table (docs/results/documented-commands.md at 4bc6404), two rows.
EARLIER = """\
# Documented commands, run

Every whole `reform-sim` command of the README and docs/ (not docs/results/), run on a fresh \
clone of 0449f13 by `python benchmarks/documented_commands.py`, each command at most 150 s.

| page:line | command | exit | seconds | longest silence (s) | verdict |
| --- | --- | ---: | ---: | ---: | --- |
| README.md:91 | `reform-sim evaluate --help  # a \\| b` | 0 | 0.2 | 0.2 | passed |
| docs/guide/twins.md:104 | `reform-sim detect --data DATASET` |  |  |  | not run: a pattern |
| docs/guide/reform.md:71 | `reform-sim train --tune` | - | 150.2 | 147.1 | timed out |
"""


@pytest.fixture
def script(documented_commands):
    return documented_commands


def test_an_earlier_table_reads_with_its_commit(script, tmp_path):
    (tmp_path / "t.md").write_text(EARLIER)
    help_, pattern, train = script.read_table(tmp_path / "t.md")
    assert help_ == script.Row(
        "README.md:91",
        "reform-sim evaluate --help  # a | b",
        "passed",
        True,
        script.Outcome(0, 0.2, 0.2, ""),
        "0449f13",
    )
    assert (pattern.passed, pattern.outcome, pattern.page) == (None, None, "docs/guide/twins.md")
    assert (train.passed, train.outcome.exit, train.outcome.silence) == (False, None, 147.1)


def test_the_table_reads_back_as_written(script, tmp_path):
    (tmp_path / "t.md").write_text(EARLIER)
    rows = script.read_table(tmp_path / "t.md")
    script.write_table(rows, tmp_path / "u.md", partial=False, timeout=60)
    assert script.read_table(tmp_path / "u.md") == rows
    assert "a fresh clone of 0449f13" in (tmp_path / "u.md").read_text()


def test_a_run_of_one_page_replaces_its_rows_alone(script, tmp_path):
    (tmp_path / "t.md").write_text(EARLIER)
    kept = script.read_table(tmp_path / "t.md")
    page = script.REPO / "docs" / "guide" / "reform.md"
    new = script.Row(
        "docs/guide/reform.md:71", "reform-sim train --tune", "passed", True,
        script.Outcome(0, 90.0, 2.1, ""), "abc1234",
    )  # fmt: skip
    rows = script.merged([new], kept, run=[page])
    assert [r.where for r in rows if r.page == "docs/guide/reform.md"] == [new.where]
    assert rows[rows.index(new)].commit == "abc1234"
    assert {r.where for r in rows} == {r.where for r in kept}
    script.write_table(rows, tmp_path / "u.md", partial=False, timeout=150)
    text = (tmp_path / "u.md").read_text()
    assert "fresh clones of 0449f13, abc1234" in text and "147.1" not in text
    assert "Longest silence: 2.1 s (docs/guide/reform.md:71)" in text


def test_only_runs_the_commands_it_matches_and_keeps_the_others_rows(script, tmp_path):
    import dataclasses
    import re

    page = script.REPO / "docs" / "bad-input.md"
    commands = [c for c in script.site_pages.commands(page.read_text()) if c.whole]
    name = "docs/bad-input.md"
    earlier = script.Outcome(0, 1.0, 1.0, "")
    kept = [
        script.Row(f"{name}:{c.line}", c.text, "passed", True, earlier, "kept") for c in commands
    ]
    chosen = [c for c in commands if "--episodes 1e9" in c.text]
    assert len(chosen) == 1  # the page's refusal of a billion stress episodes: 0.1 s
    rows = script.run_pages(
        [page], timeout=30, out=tmp_path / "t.md", kept=kept, only=re.compile(r"episodes 1e9")
    )
    ran = [r for r in rows if r.commit != "kept" and r.outcome is not None]
    assert [r.where for r in ran] == [f"{name}:{chosen[0].line}"]
    assert [r for r in rows if r.ran] == ran  # what the summary counts as run: none kept
    assert ran[0].verdict == "refused as the page shows" and ran[0].outcome.exit == 2
    patterns = [r.where for r in rows if r.verdict.startswith("not run")]  # shown, never run
    assert [r for r in rows if r.commit == "kept"] == [
        k for k in kept if k.where != ran[0].where and k.where not in patterns
    ]
    # A row follows its command when the page gains lines above it (kept rows a line early).
    moved = [dataclasses.replace(k, where=f"{name}:{int(k.where.split(':')[1]) - 1}") for k in kept]
    again = script.run_pages(
        [page], timeout=30, out=tmp_path / "u.md", kept=moved, only=re.compile(r"episodes 1e9")
    )
    assert [(r.where, r.commit) for r in again] == [(r.where, r.commit) for r in rows]
    table = [(r.where, r.verdict, r.commit) for r in script.read_table(tmp_path / "t.md")]
    assert table == [(r.where, r.verdict, r.commit) for r in rows]
