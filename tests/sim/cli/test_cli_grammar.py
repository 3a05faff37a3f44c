"""One grammar for every command (sim.cli._grammar): a walk over every subcommand's parser checks
that each concept has its one spelling, and that each old spelling still works for a release,
saying which spelling replaces it."""

from __future__ import annotations

import argparse
import re

import pytest

from sim.cli import build_parser, main
from sim.cli._common import DEFAULT_JOBS, job_count
from sim.cli._grammar import FRAME_CHOICES, RENAMED

# Spellings that the grammar replaced: none of them may be shown in a command's help.
OLD_SPELLINGS = {
    "--datasets",
    "--salsa",
    "--babble",
    "--seeds",
    "--no-progress",
    "--progress",
    "--markdown",
    "--save-recordings",
    "--annotated-only",
}
# Commands that can take over two seconds: progress on stderr, --quiet to silence it.
LONG = {
    "demo",
    "datasets fetch",
    "benchmark",
    "experiment gcff",
    "experiment paper",
    "experiment hri",
    "experiment sim2real",
    "experiment twins",
    "experiment temporal",
    "simulate",
    "generate",
    "calibrate",
    "stress",
    "policy evaluate",
    "characterize",
    "train",
    "evaluate",
    "detect",
    "tune",
    "twin",
}
# Commands that record one Rerun recording of the run: the flags of rr.script_add_args.
RECORDING = {"simulate", "evaluate", "detect", "stress"}
RERUN_FLAGS = {"--save", "--connect", "--url", "--serve", "--headless"}
# Commands that score or run on a dataset's frames: --frames all|train|test.
FRAMES = {"evaluate", "detect", "benchmark", "train"}


def _commands(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()):
    """(command words, parser) for every leaf subcommand."""
    subparsers = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subparsers:
        parser.format_help()  # adds a lazily declared subcommand's arguments
        yield " ".join(prefix), parser
        return
    for action in subparsers:
        seen = set()
        for name, sub in action.choices.items():
            if id(sub) in seen:
                continue  # an alias
            seen.add(id(sub))
            sub.format_help()
            yield from _commands(sub, (*prefix, name))


COMMANDS = dict(_commands(build_parser()))


def _visible(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [
        a
        for a in parser._actions
        if a.help is not argparse.SUPPRESS and not isinstance(a, argparse._HelpAction)
    ]


def _flags(parser: argparse.ArgumentParser) -> set[str]:
    return {flag for a in _visible(parser) for flag in a.option_strings}


def test_the_walk_finds_every_command():
    assert {"generate", "experiment sim2real", "data info", "policy evaluate"} <= set(COMMANDS)
    assert len(COMMANDS) >= 20


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_each_concept_has_its_one_spelling(command):
    parser = COMMANDS[command]
    flags = _flags(parser)
    assert not flags & OLD_SPELLINGS, f"{command} shows old spellings {flags & OLD_SPELLINGS}"
    for action in _visible(parser):
        takes_value = action.nargs != 0 and not isinstance(action, argparse.BooleanOptionalAction)
        if not action.option_strings:  # a positional: names, never the data read
            assert action.dest not in ("data", "path"), f"{command}: data as a positional"
            continue
        if takes_value and action.choices is None:
            assert action.metavar, f"{command} {action.option_strings}: no metavar"
        if "--json" in action.option_strings:
            assert action.nargs == 0, f"{command}: --json takes a path; use --out"
        if "--out" in action.option_strings:
            assert action.metavar.split("|")[0] == "DIR" or action.metavar.startswith("FILE"), (
                f"{command}: --out {action.metavar}"
            )
        if "--seed" in action.option_strings:
            assert (action.default, action.metavar, action.required) == (0, "S", False), command
        if "--frames" in action.option_strings:
            assert set(action.choices) <= set(FRAME_CHOICES), command
    assert ("--quiet" in flags) == (command in LONG), command
    if command in RECORDING:
        assert RERUN_FLAGS <= flags, f"{command} lacks {RERUN_FLAGS - flags}"
    assert ("--frames" in flags) == (command in FRAMES), command


def test_data_is_read_with_data_everywhere():
    readers = [c for c, p in COMMANDS.items() if any(a.dest == "data" for a in p._actions)]
    assert set(readers) >= {
        "data info",
        "data verify",
        "data convert",
        "evaluate",
        "detect",
        "train",
        "characterize",
        "benchmark",
        "calibrate",
        "demo",
        "experiment gcff",
        "experiment paper",
        "experiment hri",
        "experiment sim2real",
    }
    for command in readers:
        (action,) = [a for a in COMMANDS[command]._actions if a.dest == "data"]
        assert action.option_strings == ["--data"], command


def test_every_old_spelling_is_declared_and_names_its_replacement():
    assert OLD_SPELLINGS - {"--markdown"} <= set(RENAMED) | {"--progress"}
    assert all(new.startswith(("--", "(")) for new in RENAMED.values())


@pytest.mark.parametrize(
    ("argv", "attribute", "value", "new"),
    [
        (["stress", "--seeds", "3"], "episodes", 3, "--episodes"),
        (["calibrate", "--out", "o", "--seeds", "2"], "episodes", 2, "--episodes"),
        (["generate", "--scenario", "mingle", "--episodes", "1", "--out", "o", "--no-progress"],
         "quiet", True, "--quiet"),
        (["generate", "--scenario", "mingle", "--episodes", "1", "--out", "o",
          "--save-recordings"], "recordings", True, "--recordings"),
        (["experiment", "paper", "--out", "o", "--salsa", "s", "--babble", "b"],
         "data", ["salsa=s", "babble=b"], "--data"),
        (["experiment", "gcff", "--out", "o", "--datasets", "d"], "data", ["d"], "--data DIR"),
        (["demo", "--datasets", "d"], "data", "d", "--data"),
        (["evaluate", "--detector", "majority", "--data", "x", "--json", "r.json"],
         "old_json", "r.json", "--out DIR"),
        (["detect", "--detector", "majority", "--data", "x", "--out", "d.json",
          "--annotated-only"], "frames", "all", "--frames all"),
        (["policy", "evaluate", "--env", "E", "--json", "p.json"], "out", "p.json", "--out"),
    ],
)  # fmt: skip
def test_an_old_spelling_still_works_and_says_the_new_one(argv, attribute, value, new, capsys):
    args = build_parser().parse_args(argv)
    assert getattr(args, attribute) == value
    err = capsys.readouterr().err
    assert "is deprecated" in err and f"use {new}" in err


def test_a_positional_dataset_still_reads_with_a_warning(tmp_path, capsys):
    from toy_scenes import toy_frames

    from reform import Dataset, write_parquet

    path = tmp_path / "toy.parquet"
    write_parquet(Dataset(frames=tuple(toy_frames(0, 5)), name="toy", source="toy"), path)
    assert main(["data", "info", str(path)]) == 0
    captured = capsys.readouterr()
    assert f"use --data {path}" in captured.err and "dataset          toy" in captured.out
    assert main(["data", "info", str(path), "--data", str(path)]) == 2
    assert "give the dataset once" in capsys.readouterr().err


def test_help_shows_no_dest_names_as_metavars():
    for command, parser in COMMANDS.items():
        text = parser.format_help()
        for action in _visible(parser):
            if action.option_strings and action.nargs != 0 and action.dest.upper() in text:
                assert action.metavar or action.choices, f"{command}: {action.dest.upper()}"


def _option(parser: argparse.ArgumentParser, flag: str) -> argparse.Action | None:
    return next((a for a in _visible(parser) if flag in a.option_strings), None)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_jobs_out_and_recordings_keep_the_grammar(command):
    parser = COMMANDS[command]
    jobs = _option(parser, "--jobs")
    if jobs is not None:  # one default everywhere, stated in the help
        assert (jobs.default, jobs.metavar) == (None, "N"), command
        assert f"(default: {DEFAULT_JOBS})" in jobs.help, f"{command}: --jobs {jobs.help}"
    out = _option(parser, "--out")
    if out is not None and not out.required:  # an optional --out says what happens without it
        assert "(default: " in out.help, f"{command}: --out {out.help}"
    if out is not None and out.default is not None:
        assert out.metavar.startswith("DIR") and f"(default: {out.default})" in out.help, command
    saves = _option(parser, "--save") is not None
    recordings = _option(parser, "--recordings")
    assert not (saves and recordings), f"{command}: --save and --recordings"
    if saves:
        assert RERUN_FLAGS <= _flags(parser), command
    if recordings is not None:
        assert "--no-recordings" in recordings.option_strings, command
        assert re.search(r"in OUT/recordings/ \(default: (yes|no)\)$", recordings.help), command
    for flag in _flags(parser) - RERUN_FLAGS - {"--recordings", "--no-recordings"}:
        assert not re.search("record|rrd|rerun", flag), f"{command}: {flag}, a third spelling"


def test_jobs_left_out_is_every_core():
    from sim.executor import cpu_count

    args = build_parser().parse_args(["benchmark"])
    assert args.jobs is None and job_count(args) == cpu_count()
    assert job_count(build_parser().parse_args(["benchmark", "--jobs", "3"])) == 3


def test_benchmark_starts_no_more_workers_than_its_cells_pay_for(monkeypatch):
    from sim.cli._benchmark import CELLS_PER_WORKER
    from sim.cli.benchmark import _jobs

    monkeypatch.setattr("sim.executor.cpu_count", lambda: 8)
    default = build_parser().parse_args(["benchmark"])
    assert _jobs(default, cells=12) == 1  # the default detectors on the four datasets at hand
    assert _jobs(default, cells=3 * CELLS_PER_WORKER) == 3
    assert _jobs(default, cells=100 * CELLS_PER_WORKER) == 8  # every core at most
    given = build_parser().parse_args(["benchmark", "--jobs", "4"])
    assert _jobs(given, cells=1) == 4  # --jobs given is obeyed


def _mistyped(parser: argparse.ArgumentParser) -> str:
    """A long flag of the parser with an extra letter, a prefix of none of its flags."""
    flag = sorted(f for f in _flags(parser) if f.startswith("--") and f != "--help")[0]
    return flag + "x"


@pytest.mark.parametrize("command", sorted(c for c in COMMANDS if _flags(COMMANDS[c]) - {"-h"}))
def test_an_unknown_flag_names_the_closest_one(command, capsys):
    typo = _mistyped(COMMANDS[command])
    with pytest.raises(SystemExit) as stop:
        build_parser().parse_args([*command.split(), typo])
    err = capsys.readouterr().err
    assert stop.value.code == 2
    assert err.count("\n") == 1 and f"reform-sim {command}: error: " in err, err
    assert f"unrecognized arguments: {typo}; did you mean {typo[:-1]}?" in err, err


# How each command that takes a scenario's name is asked for one (a new one is added here).
SCENARIO_RUNS = {
    "simulate": ["simulate", "--out", "{out}/o.parquet", "--scenario"],
    "generate": ["generate", "--episodes", "1", "--out", "{out}", "--scenario"],
    "scenarios": ["scenarios"],
}


def test_an_unknown_scenario_gets_one_message_from_every_command(tmp_path, capsys):
    import scenarios

    takes = {c for c, p in COMMANDS.items() if "--scenario" in _flags(p)}
    assert takes and takes <= set(SCENARIO_RUNS), takes - set(SCENARIO_RUNS)
    with pytest.raises(ValueError) as registry:
        scenarios.describe("no-such-scene")
    for command, words in SCENARIO_RUNS.items():
        out = tmp_path / command
        assert main([w.format(out=out) for w in words] + ["no-such-scene"]) == 2, command
        err = capsys.readouterr().err
        assert err == f"reform-sim {command}: error: {registry.value}\n", (command, err)
        assert not out.exists(), f"{command} wrote before refusing"
