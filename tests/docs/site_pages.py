"""The runnable code blocks of the site's tutorial pages, as the tests run them.

A page's fenced ``bash`` and ``python`` blocks run in order, in one empty folder:

* a ``bash`` block with ``bash -euo pipefail`` (``reform-sim`` is the installed command);
* the ``python`` blocks of a page in one interpreter, one after the other, sharing names;
* a block whose fence carries ``title="PATH"`` is a file the page asks you to write: it is
  written to PATH, not run;
* a block right after an HTML comment ``<!-- not run: REASON -->`` is skipped (kept for what
  cannot run here: a download, a window);
* blocks of other languages (``text``, ``toml``) are shown, not run.

A page that needs the field's real datasets says so with ``<!-- needs: datasets -->``.

The ``reform-sim`` commands every page shows, in its blocks and inline, are :func:`commands`
(``test_documented_commands.py`` parses them, ``benchmarks/documented_commands.py`` runs them).
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass
from pathlib import Path

DOCS = Path(__file__).resolve().parents[2] / "docs"
REPO = DOCS.parent
# The pages whose commands are checked: the README and every page but the results', whose
# commands are the records of past runs.
COMMAND_PAGES = (
    REPO / "README.md",
    *sorted(p for p in DOCS.rglob("*.md") if p.parent.name != "results"),
)
# The pages whose blocks run: getting started and every tutorial.
RUNNABLE_PAGES = (
    "getting-started.md",
    *sorted(str(p.relative_to(DOCS)) for p in (DOCS / "tutorials").glob("*.md")),
)
RUN_LANGUAGES = ("bash", "python")
NEEDS_DATASETS = "<!-- needs: datasets -->"

_FENCE = re.compile(r"^(?P<indent> *)(?P<fence>```+)(?P<info>[^`]*)$")
_NOT_RUN = re.compile(r"^\s*<!-- not run: .+ -->\s*$")
_TITLE = re.compile(r'title="(?P<path>[^"]+)"')
# Words that mark a line as a pattern rather than a command (alternatives, elisions, prompts).
_PLACEHOLDER = re.compile(r"\.\.\.|…|<[A-Za-z]|\|(?!\|)|\[--|\bNAME\b(?!=)|\$\w")
_REFUSAL = re.compile(r"reform-sim [\w ]+: error:")


@dataclass(frozen=True)
class Block:
    """One fenced code block of a page.

    Attributes:
        language: the fence's first word (``bash``, ``python``, ``text``, ...).
        code: the block's text, without its indentation.
        line: the line of its opening fence (1-based).
        title: the file it is to be written to (``title="..."``), or None.
        skipped: marked ``<!-- not run: ... -->``.
    """

    language: str
    code: str
    line: int
    title: str | None
    skipped: bool

    @property
    def runs(self) -> bool:
        return self.language in RUN_LANGUAGES and self.title is None and not self.skipped


def blocks(text: str) -> list[Block]:
    """The fenced code blocks of a Markdown page, in order."""
    lines = text.split("\n")
    out: list[Block] = []
    i = 0
    while i < len(lines):
        match = _FENCE.match(lines[i])
        if match is None or not match["info"].strip():
            i += 1
            continue
        indent, fence, info = len(match["indent"]), match["fence"], match["info"].strip()
        start = i
        body = []
        i += 1
        while i < len(lines) and lines[i].strip() != fence:
            body.append(lines[i][indent:])
            i += 1
        before = next((lines[k] for k in range(start - 1, -1, -1) if lines[k].strip()), "")
        title = _TITLE.search(info)
        out.append(
            Block(
                language=info.split()[0].strip("{}."),
                code="\n".join(body) + "\n",
                line=start + 1,
                title=title["path"] if title else None,
                skipped=bool(_NOT_RUN.match(before)),
            )
        )
        i += 1
    return out


def page_script(text: str) -> str:
    """A Python program that does what the page's blocks do, in order, in its current folder,
    each block announced on stderr with its line so that a failure names it."""
    steps = ["import pathlib, subprocess, sys", "_page = {}"]
    for block in blocks(text):
        if block.title is not None:
            steps.append(
                f"pathlib.Path({block.title!r}).parent.mkdir(parents=True, exist_ok=True)\n"
                f"pathlib.Path({block.title!r}).write_text({block.code!r})"
            )
        elif block.runs and block.language == "bash":
            steps.append(
                f"print('--- line {block.line}: bash', file=sys.stderr, flush=True)\n"
                f"subprocess.run(['bash', '-euo', 'pipefail', '-c', {block.code!r}], check=True)"
            )
        elif block.runs:
            steps.append(
                f"print('--- line {block.line}: python', file=sys.stderr, flush=True)\n"
                f"exec(compile({block.code!r}, 'line {block.line}', 'exec'), _page)"
            )
    return "\n".join(steps) + "\n"


@dataclass(frozen=True)
class Command:
    """One ``reform-sim`` command a page shows.

    Attributes:
        line: its line on the page (1-based).
        text: the command as a user types it (a continuation joined, a ``$`` prompt dropped).
        whole: in a code block, whole; else inline in the text, perhaps a fragment
            (``reform-sim generate --twin``) whose other flags the text leaves out.
        refusal: the ``reform-sim X: error: ...`` line the page shows right after it (bad
            input shown with its refusal, docs/bad-input.md), or None.
    """

    line: int
    text: str
    whole: bool
    refusal: str | None = None


def commands(text: str) -> list[Command]:
    """The ``reform-sim`` commands of a page: its code blocks' whole ones, then its inline ones."""
    found = []
    for block in blocks(text):
        if block.title is not None:
            continue
        lines = block.code.split("\n")
        k = 0
        while k < len(lines):
            start, line = k, lines[k]
            while line.rstrip().endswith("\\") and k + 1 < len(lines):
                k += 1
                line = line.rstrip()[:-1] + " " + lines[k].strip()
            k += 1
            line = line.strip().removeprefix("$ ")
            answer = lines[k].strip() if k < len(lines) else ""
            refusal = answer if _REFUSAL.match(answer) else None
            if line.startswith("reform-sim ") and not _REFUSAL.match(line):
                found.append(Command(block.line + 1 + start, line, True, refusal))
            k += refusal is not None  # the refusal is the page's answer, not a command
    for n, line in enumerate(text.split("\n"), start=1):
        found += [Command(n, m, False) for m in re.findall(r"`(reform-sim [^`]+)`", line)]
    return found


def command_words(command: str) -> list[str] | None:
    """The command's words after ``reform-sim``, or None when it is a pattern or a pipeline."""
    command = re.split(r"\s+#", command)[0]
    for stop in (" | ", " && ", " > ", " 2>", "; "):
        command = command.split(stop)[0]
    if _PLACEHOLDER.search(command) or re.match(r"reform-sim [\w ]+: ", command):
        return None  # a pattern, or an error message quoted
    try:
        return shlex.split(command)[1:]
    except ValueError:
        return None
