"""Every ``reform-sim`` command the README and the documentation show, run as a user runs it on a
fresh clone: its exit status, its time and its longest silence (issue 33).

The commands are those ``tests/docs/test_documented_commands.py`` parses (``site_pages``): the
whole ones of each page's code blocks, not the fragments in its text. A page's commands run in
the page's order in one fresh folder of the page's own: a clone of the repository's HEAD, beside
a ``shared/datasets`` link to the datasets (the layout ``../shared/datasets`` on the pages
assumes), each in a new shell with the virtualenv's bin first on PATH, ``REFORM_SIM_DATASETS``
set and the clone's code imported (``PYTHONPATH``), on a terminal of its own as a user's (a
short command shows its progress lines only on a terminal). Every page's clone is of one commit,
HEAD when the run starts. A command run before, on this page or an earlier one (comments and
spacing aside), is not run again, unless it writes files (``--out``, ``--save``) that the page's
next commands may read. The files a page asks its reader to write (its blocks with
``title="PATH"``) are written in its folder before its first command. A pattern, or a command with a
placeholder for the user's own value (``--data PATH``), is shown, not run.

Per command: the exit status, the wall time, and the longest silence: the largest gap between
two consecutive lines of its output (stdout and stderr; a progress bar's redraw is a line), the
start and the exit included. A command passes when it exits 0, or when it is refused as the page
documents: the page shows a ``reform-sim X: error:`` line right after it and the command exits
non-zero with a last line ``reform-sim X: error: ...``. A command still running at --timeout is
stopped and counted "timed out", never passed.

The table (page:line, commit, command, exit, seconds, longest silence, verdict) is written to
--out after each page, whole or not at all, so an interrupted run leaves the table of what ran,
marked partial. With --update, the rows --out already holds for the pages this run does not run
are kept, each with the commit it ran on, so that a run of a few pages refreshes theirs in the
whole table; with ``--only REGEX`` as well, only the commands matching REGEX run on those pages
and the others keep their rows (the long commands a busy run stopped, run again on their own).
One line is printed per command as it finishes, and a summary at the end.

Run: ``python benchmarks/documented_commands.py [--pages GLOB ...] [--timeout S] [--out FILE]
[--update [--only REGEX]] [--quick]`` (``--quick``: the README's commands only; a glob is
relative to the repository, pages in the order of the globs given).
"""

from __future__ import annotations

import dataclasses
import fcntl
import importlib.util
import os
import pty
import re
import select
import signal
import struct
import subprocess
import sys
import tempfile
import termios
import time
from dataclasses import dataclass
from pathlib import Path

from timing import DATASETS_VARIABLE, REPO, BenchmarkParser, default_datasets

from sim.experiments.report_files import write_markdown

SILENCE_GOAL_S = 5.0  # seconds: issue 33's longest silence of any documented command
EXIT_GRACE_S = 5.0  # seconds its terminal may stay open after the command exits (a child's)
TAIL_BYTES = 65_536  # of output kept to read the refusal line
TERMINAL_SIZE = (50, 120)  # rows, columns of the terminal the commands run on
_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")  # a terminal's colour and cursor codes
# A word standing for the user's own value: --data PATH, --tune-on TRAIN, detector=NAME.
_PLACEHOLDER = re.compile(r"^(?:[\w-]+=)?[A-Z][A-Z_]{2,}/?$")
_REFUSAL = re.compile(r"^(reform-sim [\w ]+): error:")
# A command that writes files, which the page's next commands may read: run on every page.
_WRITES = re.compile(r"\s--(?:out|save)\b")


def _site_pages():
    """``tests/docs/site_pages.py``: how the tests read the pages (not a package: by path)."""
    path = REPO / "tests" / "docs" / "site_pages.py"
    spec = importlib.util.spec_from_file_location("site_pages", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


site_pages = _site_pages()


@dataclass(frozen=True)
class Outcome:
    """How one run of a command went.

    Attributes:
        exit: its exit status; None when it timed out.
        seconds: wall time from start to exit, seconds.
        silence: longest gap between consecutive lines of output, start and exit included, s.
        last_line: the last non-empty line of its output, for a refusal.
        quiet_after: the last line before its longest silence ("" for the start): where to
            look when the silence is too long.
    """

    exit: int | None
    seconds: float
    silence: float
    last_line: str
    quiet_after: str = ""


@dataclass(frozen=True)
class Row:
    """One command of a page and its verdict; ``outcome`` None when it was not run."""

    where: str
    command: str
    verdict: str
    passed: bool | None  # None: not run
    outcome: Outcome | None = None
    commit: str = ""  # the commit of the clone it ran on
    ran: bool = dataclasses.field(default=False, compare=False)  # run by this run (not a table's)

    @property
    def page(self) -> str:
        return self.where.rpartition(":")[0]


def run_command(command: str, *, cwd: Path, env: dict[str, str], timeout: float) -> Outcome:
    """Runs ``command`` in a new shell in ``cwd`` on a terminal of its own, reading its output
    line by line as it comes.

    A terminal, as a user's: a short command shows its progress lines only there. A line ends
    at a newline or a carriage return (a progress bar's redraw). The command and its children
    are stopped at ``timeout`` seconds, or ``EXIT_GRACE_S`` after it exits while a child still
    holds the terminal open.
    """
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", *TERMINAL_SIZE, 0, 0))
    start = time.monotonic()
    process = subprocess.Popen(
        ["bash", "-o", "pipefail", "-c", command],
        cwd=cwd,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=slave,
        stderr=slave,
        start_new_session=True,  # its own process group, stopped whole
    )
    os.close(slave)
    tail, last_line_at, silence, quiet_after = b"", start, 0.0, ""
    exited_at, timed_out = None, False
    while True:
        now = time.monotonic()
        if exited_at is None and process.poll() is not None:
            exited_at = now
        if exited_at is not None and now - exited_at > EXIT_GRACE_S:
            break  # a child still holds the terminal: stopped below
        if now - start > timeout:
            timed_out = exited_at is None
            break
        if not select.select([master], [], [], 0.5)[0]:
            continue
        try:
            chunk = os.read(master, 65_536)
        except OSError:  # EIO: every holder of the terminal has closed it
            chunk = b""
        if not chunk:
            try:
                process.wait(timeout=max(0.0, timeout - (time.monotonic() - start)))
            except subprocess.TimeoutExpired:
                timed_out = True
            break
        before, tail = tail, (tail + chunk)[-TAIL_BYTES:]
        if b"\n" in chunk or b"\r" in chunk:
            now = time.monotonic()
            if now - last_line_at > silence:
                silence, quiet_after = now - last_line_at, _last_line(before)
            last_line_at = now
    if exited_at is None and not timed_out:
        exited_at = time.monotonic()
    os.close(master)
    try:
        os.killpg(process.pid, signal.SIGKILL)  # the command's own group: what it left behind
    except ProcessLookupError:
        pass
    status = process.wait()
    end = time.monotonic() if timed_out else exited_at
    if end - last_line_at > silence:
        silence, quiet_after = end - last_line_at, _last_line(tail)
    return Outcome(
        exit=None if timed_out else status,
        seconds=end - start,
        silence=silence,
        last_line=_last_line(tail),
        quiet_after=quiet_after,
    )


def _last_line(output: bytes) -> str:
    """The last non-empty line of a terminal's ``output``, its colour codes removed."""
    text = _ANSI.sub("", output.decode("utf-8", "replace"))
    lines = [line.strip() for line in re.split(r"[\r\n]", text) if line.strip()]
    return lines[-1] if lines else ""


def verdict(outcome: Outcome, refusal: str | None) -> tuple[str, bool]:
    """The verdict on a run and whether it passes: exit 0, or the refusal the page shows."""
    if outcome.exit is None:
        return "timed out", False
    if outcome.exit == 0:
        return "passed", True
    shown = _REFUSAL.match(refusal or "")
    said = _REFUSAL.match(outcome.last_line)
    if shown and said and shown[1] == said[1]:
        return "refused as the page shows", True
    return f"failed: {outcome.last_line[:300]}", False


def _normalised(command: str) -> str:
    return " ".join(re.split(r"\s+#", command)[0].split())


def _clone(source: Path, folder: Path) -> Path:
    """A clone of ``source``'s HEAD in ``folder``."""
    subprocess.run(["git", "clone", "--quiet", str(source), str(folder)], check=True)
    return folder


def _page_folder(source: Path, folder: Path, page: str) -> Path:
    """A clone of ``source`` in ``folder`` holding the files the ``page`` (its text) asks its
    reader to write (its blocks with ``title="PATH"``)."""
    _clone(source, folder)
    for block in site_pages.blocks(page):
        if block.title is not None:
            (folder / block.title).parent.mkdir(parents=True, exist_ok=True)
            (folder / block.title).write_text(block.code, encoding="utf-8")
    return folder


def _environment(clone: Path) -> dict[str, str]:
    """A new shell's: the virtualenv first on PATH, the datasets, the clone's code."""
    venv_bin = Path(sys.executable).parent
    return {
        "PATH": f"{venv_bin}:/usr/local/bin:/usr/bin:/bin",
        "HOME": os.environ.get("HOME", str(clone)),
        "LANG": os.environ.get("LANG", "C.UTF-8"),
        "TERM": "xterm",
        DATASETS_VARIABLE: str(Path(default_datasets()).resolve()),
        "PYTHONPATH": str(clone),
        "TMPDIR": str(clone.parent),
    }


def pages_of(globs: list[str]) -> list[Path]:
    """The pages matching ``globs`` (relative to the repository), in the order of the globs."""
    pages = []
    for glob in globs:
        pages += [p for p in sorted(REPO.glob(glob)) if p in site_pages.COMMAND_PAGES]
    return list(dict.fromkeys(pages))


def run_pages(
    pages: list[Path],
    *,
    timeout: float,
    out: Path,
    kept: list[Row] | None = None,
    only: re.Pattern[str] | None = None,
) -> list[Row]:
    """Runs every page's whole commands; prints a line per command; rewrites ``out`` per page,
    with the rows of ``kept`` whose pages this run does not run (`merged`). With ``only``, a
    command it does not match keeps its row of ``kept`` (same page, same command, the next
    such row in page order, at the command's line now) if there is one, and is run
    otherwise."""
    # By page and command, in page order: a row follows its command when lines move above it.
    before: dict[tuple[str, str], list[Row]] = {}
    for r in kept or []:
        before.setdefault((r.page, _normalised(r.command)), []).append(r)
    rows: list[Row] = []
    done: dict[str, Row] = {}  # normalised command -> the row that ran it
    n_commands = sum(
        c.whole for p in pages for c in site_pages.commands(p.read_text(encoding="utf-8"))
    )
    with tempfile.TemporaryDirectory(prefix="documented-commands-") as parent:
        source = _clone(REPO, Path(parent) / "source")  # one commit for every page
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=source, capture_output=True, text=True
        ).stdout.strip()
        (Path(parent) / "shared").mkdir()
        (Path(parent) / "shared" / "datasets").symlink_to(Path(default_datasets()).resolve())
        for k, page in enumerate(pages):
            name = str(page.relative_to(REPO))
            if not (source / name).is_file():
                continue  # a page not committed yet: a fresh clone has none
            text = (source / name).read_text(encoding="utf-8")  # the page as the clone has it
            clone = None
            for command in site_pages.commands(text):
                if not command.whole:
                    continue
                where = f"{name}:{command.line}"
                words = site_pages.command_words(command.text)
                key = _normalised(command.text)
                if words is None or any(_PLACEHOLDER.match(w) for w in words):
                    said = "not run: a pattern or a placeholder"
                    row = Row(where, command.text, said, None, None, commit)
                elif only is not None and not only.search(key) and before.get((name, key)):
                    row = dataclasses.replace(before[name, key].pop(0), where=where)
                elif key in done and not _WRITES.search(key):
                    first = done[key]
                    said = f"as {first.where}"
                    row = Row(where, command.text, said, None, first.outcome, commit)
                else:
                    if clone is None:
                        clone = _page_folder(source, Path(parent) / f"page{k}", text)
                    outcome = run_command(
                        command.text, cwd=clone, env=_environment(clone), timeout=timeout
                    )
                    said, passed = verdict(outcome, command.refusal)
                    row = done[key] = Row(
                        where, command.text, said, passed, outcome, commit, ran=True
                    )
                rows.append(row)
                _print_row(row, len(rows), n_commands)
            table = merged(rows, kept or [], run=pages[: k + 1])
            write_table(table, out, partial=k + 1 < len(pages), timeout=timeout)
    return rows


def merged(rows: list[Row], kept: list[Row], *, run: list[Path]) -> list[Row]:
    """``rows``, and the rows of ``kept`` whose pages are not among the pages ``run``, page by
    page in the order of the site's pages (a page no longer among them is left out)."""
    names = {str(p.relative_to(REPO)) for p in run}
    by_page: dict[str, list[Row]] = {}
    for row in [r for r in kept if r.page not in names] + rows:
        by_page.setdefault(row.page, []).append(row)
    order = [str(p.relative_to(REPO)) for p in site_pages.COMMAND_PAGES]
    return [row for page in order for row in by_page.get(page, [])]


_CELL_SPLIT = re.compile(r"(?<!\\)\|")
_COMMIT = re.compile(r"fresh clones? of (\w+)")


def read_table(path: Path) -> list[Row]:
    """The rows of a table `write_table` wrote (or its earlier form, without a commit column:
    every row then of the commit its first paragraph names); none when ``path`` is missing."""
    if not path.is_file():
        return []
    text = path.read_text(encoding="utf-8")
    found = _COMMIT.search(text)
    header_commit = found[1] if found else ""
    rows = []
    for line in text.splitlines():
        if not line.startswith("| ") or line.startswith(("| page:line", "| ---")):
            continue
        cells = [c.strip().replace("\\|", "|") for c in _CELL_SPLIT.split(line)[1:-1]]
        if len(cells) == 6:  # the earlier form
            cells.insert(1, header_commit)
        where, commit, command, exit_, seconds, silence, said = cells
        command = command.strip("`")
        outcome = None
        if seconds:
            status = None if exit_ == "-" else int(exit_)
            outcome = Outcome(status, float(seconds), float(silence), "")
        if said == "passed" or said.startswith("refused"):
            passed = True
        elif said.startswith(("not run", "as ")):
            passed = None
        else:
            passed = False
        rows.append(Row(where, command, said, passed, outcome, commit))
    return rows


def _print_row(row: Row, n: int, total: int) -> None:
    figures = ""
    if row.outcome is not None and row.passed is not None:
        o = row.outcome
        exit_ = "-" if o.exit is None else o.exit
        figures = f"exit {exit_}  {o.seconds:.1f} s  silence {o.silence:.1f} s  "
        if o.silence >= SILENCE_GOAL_S:
            figures += f"(after {o.quiet_after[:80] or 'the start'!r})  "
    print(f"[{n}/{total}] {row.where}  {figures}{row.verdict}  ({row.command[:80]})", flush=True)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def write_table(rows: list[Row], out: Path, *, partial: bool, timeout: float) -> None:
    """Writes the Markdown table of ``rows`` to ``out``, whole or not at all."""
    run = [r for r in rows if r.passed is not None]
    loudest = max(run, key=lambda r: r.outcome.silence, default=None)
    commits = list(dict.fromkeys(r.commit for r in rows if r.commit))
    clones = (
        f"a fresh clone of {commits[0]}"
        if len(commits) == 1
        else f"fresh clones of {', '.join(commits)} (each row's commit beside it)"
    )
    lines = [
        "# Documented commands, run",
        "",
        f"Every whole `reform-sim` command of the README and docs/ (not docs/results/), run on "
        f"{clones} by `python benchmarks/documented_commands.py`, each page in its "
        f"own folder, each command at most {timeout:g} s in the latest run. "
        f"{'**Partial: the run was stopped before its last page.** ' if partial else ''}"
        f"{len(run)} commands run, {sum(r.passed for r in run)} passed, "
        f"{sum(not r.passed for r in run)} failed or timed out; "
        f"{sum(r.passed is None and r.outcome is None for r in rows)} not run (patterns).",
    ]
    if loudest is not None:
        lines[-1] += (
            f" Longest silence: {loudest.outcome.silence:.1f} s ({loudest.where}); "
            f"goal under {SILENCE_GOAL_S:g} s."
        )
    lines += [
        "",
        "| page:line | commit | command | exit | seconds | longest silence (s) | verdict |",
        "| --- | --- | --- | ---: | ---: | ---: | --- |",
    ]
    for row in rows:
        o = row.outcome
        exit_ = "" if o is None else ("-" if o.exit is None else str(o.exit))
        seconds = "" if o is None else f"{o.seconds:.1f}"
        silence = "" if o is None else f"{o.silence:.1f}"
        lines.append(
            f"| {row.where} | {row.commit} | `{_cell(row.command)}` | {exit_} | {seconds} | "
            f"{silence} | {_cell(row.verdict)} |"
        )
    write_markdown(out, "\n".join(lines) + "\n")


def main() -> None:
    parser = BenchmarkParser(__doc__)
    parser.add_argument(
        "--pages",
        action="append",
        metavar="GLOB",
        help="pages to run, relative to the repository; repeat for more, run in the order "
        "given (default: the README, then docs/ but docs/results/; with --quick the README)",
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=1800.0,
        metavar="S",
        help="seconds a command may run before it is stopped and counted timed out (default 1800)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=REPO / "docs" / "results" / "documented-commands.md",
        help="the Markdown table (default docs/results/documented-commands.md)",
    )
    parser.add_argument(
        "--update",
        action="store_true",
        help="keep the rows --out holds for the pages not run, each with its commit",
    )
    parser.add_argument(
        "--only",
        type=re.compile,
        metavar="REGEX",
        help="with --update: on the pages run, run only the commands REGEX matches (Python "
        "regular expression); the others keep the rows --out holds",
    )
    args = parser.parse_args()
    if args.only is not None and not args.update:
        parser.error("--only keeps the other commands' rows: give it with --update")
    if args.pages:
        pages = pages_of(args.pages)
    elif args.quick:
        pages = [REPO / "README.md"]
    else:
        pages = list(site_pages.COMMAND_PAGES)
    if not pages:
        parser.error(f"--pages: no page with commands matches {args.pages}")
    kept = read_table(args.out) if args.update else None
    rows = run_pages(pages, timeout=args.timeout, out=args.out, kept=kept, only=args.only)
    run = [r for r in rows if r.ran]
    failed = [r for r in run if not r.passed]
    print(
        f"{len(run)} commands run, {len(run) - len(failed)} passed, {len(failed)} failed "
        f"(timed out included), {len(rows) - len(run)} not run, run before or kept; "
        f"table: {args.out}"
    )
    if run:
        loudest = max(run, key=lambda r: r.outcome.silence)
        goal = "met" if loudest.outcome.silence < SILENCE_GOAL_S else "NOT met"
        print(
            f"longest silence {loudest.outcome.silence:.1f} s: {loudest.where} "
            f"({loudest.command}); goal under {SILENCE_GOAL_S:g} s: {goal}"
        )
    for row in failed:
        print(f"failed: {row.where}: {row.verdict}")
    raise SystemExit(1 if failed else 0)


if __name__ == "__main__":
    main()
