"""sim.sizing: sizes in words, this machine, estimates, refusals; the simulation's and the
generator's requests sized before they run, and the streamed episode that keeps memory bounded."""

from __future__ import annotations

import re

import numpy as np
import pyarrow.parquet as pq
import pytest
from quiet_generate import generate_quietly
from traced import raised_peak

import reform.machine
import sim.episode
from reform.datasets import read_parquet
from sim import sizing
from sim.cli import main
from sim.episode import (
    estimate_episode,
    simulate_episode,
    stream_episode,
    write_episode,
)
from sim.generate import generate_dataset
from sim.sizing import RequestTooLarge

GiB = 2**30
REFUSAL_PEAK_BYTES = 50 * 2**20  # bytes: what a refused request may allocate while refused


# --------------------------------------------------------------------------------------------
# Sizes in words


@pytest.mark.parametrize(
    ("text", "size"),
    [
        ("8G", 8 * GiB),
        ("8g", 8 * GiB),
        ("512M", 512 * 2**20),
        ("1.5GiB", 3 * 2**29),
        ("2 TB", 2 * 2**40),
        ("1000000", 1_000_000),
        ("64k", 65_536),
        ("10B", 10),
        ("8E", 8 * 2**60),
    ],
)
def test_parse_size(text, size):
    assert sizing.parse_size(text) == size


@pytest.mark.parametrize(
    "text",
    # '\u0663' is an Arabic-Indic 3: a digit to Python's int(), never one in a size
    ["", "8X", "G", "-1G", "0", "8 GiBs", "1e9", "8iB", "\u0663", "\u0663G", "9E", "9" * 5000],
)
def test_parse_size_refuses_what_is_not_a_size(text):
    with pytest.raises(ValueError, match=r"expected a size|at least 1 byte") as caught:
        sizing.parse_size(text)  # 5,000 nines overflowed a float into a traceback
    assert len(str(caught.value)) < 120


@pytest.mark.parametrize(
    ("size", "text"),
    [
        (0, "0 B"),
        (1023, "1023 B"),
        (1536, "1.5 KiB"),
        (1010 * 1024, "1010 KiB"),
        (999.4 * 1024, "999 KiB"),
        (8 * GiB, "8 GiB"),
        (3.6 * 2**40, "3.6 TiB"),
        (2.0**70, "1.02e+03 EiB"),
    ],
)
def test_format_size(size, text):
    assert sizing.format_size(size) == text


@pytest.mark.parametrize(
    ("seconds", "text"),
    [(0.5, "0.5 s"), (41, "41 s"), (720, "12 min"), (3.2 * 3600, "3.2 h"), (41 * 86400, "41 days")],
)
def test_format_duration(seconds, text):
    assert sizing.format_duration(seconds) == text


def test_count_is_readable_at_any_size():
    assert sizing.count(1_200) == "1,200"
    assert sizing.count(2 * 10**300) == "2e+300"


# --------------------------------------------------------------------------------------------
# This machine


def test_memory_is_read_from_proc_meminfo(tmp_path, monkeypatch):
    meminfo = tmp_path / "meminfo"
    meminfo.write_text(
        "MemTotal:       24683584 kB\nMemFree:         1000000 kB\n"
        "MemAvailable:   22518916 kB\nSwapTotal:       1048576 kB\n"
    )
    monkeypatch.setattr(reform.machine, "_MEMINFO", meminfo)
    assert sizing.available_memory() == 22518916 * 1024
    assert sizing.total_memory() == (24683584 + 1048576) * 1024


def test_memory_and_disk_of_this_machine_are_positive(tmp_path):
    assert 0 < sizing.available_memory() <= sizing.total_memory()
    assert sizing.free_disk(tmp_path / "not" / "yet" / "there.parquet") > 0


# --------------------------------------------------------------------------------------------
# Estimates


def test_held_frames_grow_with_the_episode_streamed_ones_do_not():
    shape = dict(agents=19, steps_per_frame=50, schedule_rows=500)
    short = sizing.episode_estimate(frames=1_200, held_frames=1_200, **shape)
    long = sizing.episode_estimate(frames=120_000, held_frames=120_000, **shape)
    streamed = sizing.episode_estimate(frames=120_000, held_frames=1_000, **shape)
    per_frame = sizing.FRAME_BYTES + 19 * sizing.AGENT_FRAME_BYTES
    assert long.memory - short.memory == pytest.approx(118_800 * per_frame)
    assert streamed.memory < short.memory
    rows = sizing.DISK_EPISODE_BYTES  # the file's own bytes, beside its rows
    assert long.disk - rows == pytest.approx(100 * (short.disk - rows))
    assert "120,000 frames of 19 agents held in memory" == long.memory_cause
    assert "1,000 frames of 19 agents held in memory" == streamed.memory_cause


def test_the_robot_view_holds_two_frames_and_costs_its_rays():
    shape = dict(agents=19, frames=1_000, steps_per_frame=50, schedule_rows=1, held_frames=1_000)
    truth = sizing.episode_estimate(view="truth", **shape)
    robot = sizing.episode_estimate(view="robot", **shape)
    assert sizing.frame_bytes(19, view="robot") == 2 * sizing.frame_bytes(19)
    assert robot.seconds - truth.seconds == pytest.approx(
        1_000 * 19 * sizing.SECONDS_PER_OBSERVED_AGENT_FRAME
    )


def test_a_tiny_step_is_sized_by_the_worlds_schedule():
    estimate = sizing.episode_estimate(
        agents=18, frames=1_200, steps_per_frame=5 * 10**11, schedule_rows=1, held_frames=1_000
    )
    assert (
        estimate.memory_cause == "the world's schedule of 500,000,000,000 control steps per frame"
    )
    assert estimate.memory > 5 * 10**11 * sizing.SCHEDULE_BYTES_PER_STEP


def test_absurd_requests_are_sized_without_overflow():
    estimate = sizing.episode_estimate(
        agents=18, frames=2 * 10**300, steps_per_frame=2**62, schedule_rows=500, held_frames=1
    )
    assert estimate.seconds > 1e300
    assert estimate.memory_cause == "the world's schedule of 4.61e+18 control steps per frame"
    assert (
        sizing.format_size(estimate.disk) == "1.81e+285 EiB"
    )  # 2e300 frames of 18 agents, 58 B each


def test_a_dataset_is_its_episodes_and_its_card():
    one = sizing.episode_estimate(
        agents=10, frames=600, steps_per_frame=50, schedule_rows=500, held_frames=600
    )
    many = sizing.dataset_estimate(one, episodes=10**9, workers=4)
    assert many.memory == pytest.approx(4 * one.memory + 10**9 * sizing.CARD_EPISODE_BYTES)
    assert many.memory_cause == "the dataset card's entries for 1,000,000,000 episodes"
    assert many.seconds == pytest.approx(10**9 * one.seconds / 4)
    few = sizing.dataset_estimate(one, episodes=3, workers=8)
    assert few.memory == pytest.approx(3 * one.memory + 3 * sizing.CARD_EPISODE_BYTES)
    assert few.memory_cause.startswith("3 workers, each with 600 frames of 10 agents")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(agents=-1), r"agents must be an int >= 0, got -1"),
        (dict(frames=1.5), r"frames must be an int >= 0, got 1.5"),
        (dict(view="sky"), r"view must be one of \('truth', 'robot'\), got 'sky'"),
    ],
)
def test_episode_estimate_bad_input(kwargs, match):
    shape = dict(agents=2, frames=10, steps_per_frame=5, schedule_rows=1, held_frames=10)
    with pytest.raises(ValueError, match=match):
        sizing.episode_estimate(**(shape | kwargs))


# --------------------------------------------------------------------------------------------
# Refusals


def estimate(**overrides) -> sizing.Estimate:
    fields = dict(
        memory=40 * GiB,
        memory_cause="2,000 frames of 9 agents held in memory",
        disk=GiB,
        seconds=10.0,
        frames=2_000,
        agents=9,
    )
    return sizing.Estimate(**(fields | overrides))


def test_memory_refusal_names_the_estimate_the_limit_and_the_ways_out(machine):
    with pytest.raises(RequestTooLarge) as info:
        sizing.check(
            estimate(),
            shrink="a shorter {duration}",
            alternative="drop {save} to stream",
        )
    refusal = info.value
    assert (refusal.resource, refusal.needed, refusal.limit) == ("memory", 40 * GiB, 16 * GiB)
    assert str(refusal) == (
        "the run needs about 40 GiB of memory (2,000 frames of 9 agents held in memory), more "
        "than the 16 GiB of memory this machine has available; ask for less (a shorter "
        "duration), drop save to stream, or change the limit with max_memory SIZE (e.g. 64G)"
    )
    flags = refusal.message(sizing.flag_name)
    assert "(a shorter --duration), drop --save to stream, or change the limit with " in flags
    assert flags.endswith("--max-memory SIZE (e.g. 64G)")


def test_a_memory_limit_lowers_or_raises_the_bar(machine):
    with pytest.raises(RequestTooLarge, match=r"more than the limit max_memory 1 GiB;"):
        sizing.check(estimate(memory=2 * GiB), shrink="less", memory_limit=GiB)
    sizing.check(estimate(memory=40 * GiB), shrink="less", memory_limit=64 * GiB)


def test_disk_refusal_names_the_output(machine, tmp_path):
    with pytest.raises(RequestTooLarge) as info:
        sizing.check(estimate(memory=GiB, disk=2 * 2**40), shrink="less", out=tmp_path / "a")
    assert info.value.message(sizing.flag_name) == (
        "the run writes about 2 TiB (2,000 frames of 9 agents), more than the 100 GiB free "
        f"where --out {tmp_path / 'a'} is; ask for less (less) or write elsewhere"
    )
    # What is there already is not written again.
    sizing.check(estimate(memory=GiB, disk=2 * 2**40), shrink="", out=tmp_path, disk_needed=GiB)


def test_time_refusal_names_the_bound(machine):
    with pytest.raises(RequestTooLarge) as info:
        sizing.check(estimate(memory=GiB, seconds=41 * 86400.0), shrink="fewer {episodes}")
    assert info.value.message(sizing.flag_name) == (
        "the run would take about 41 days on this machine (2,000 frames of 9 agents), more "
        "than the 7 days a run may take (sim.sizing.MAX_RUN_SECONDS); ask for less (fewer "
        "--episodes)"
    )


def test_library_calls_are_refused_only_what_can_never_fit(machine):
    sizing.check_possible(estimate(memory=30 * GiB), what="it", shrink="less")
    with pytest.raises(RequestTooLarge, match=r"more than the 32 GiB of memory and swap"):
        sizing.check_possible(estimate(memory=40 * GiB), what="it", shrink="less")


def test_a_small_request_passes(machine, tmp_path):
    sizing.check(estimate(memory=GiB), shrink="less", out=tmp_path)


# --------------------------------------------------------------------------------------------
# The simulation sized before it runs


def test_an_episode_is_estimated_from_its_arguments():
    estimate = estimate_episode("mingle", seed=1)
    assert (estimate.frames, estimate.agents) == (1_200, 18)
    streamed = estimate_episode("mingle", seed=1, duration=6000.0, streamed=True)
    assert streamed.frames == 12_000
    assert streamed.memory < estimate_episode("mingle", seed=1, duration=6000.0).memory


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda: simulate_episode("mingle", seed=1, dt=1e-12),
            r"mingle for 600 s at 2 Hz \(dt 1e-12 s\) needs about 3\.64 TiB of memory \(the "
            r"world's schedule of 500,000,000,000 control steps per frame\), more than the 32 "
            r"GiB of memory and swap this machine has; ask for less \(a shorter duration, a "
            r"lower rate or a larger dt\)",
        ),
        (
            lambda: simulate_episode("mingle", seed=1, duration=1e9),
            r"mingle for 1e\+09 s at 2 Hz \(dt 0.01 s\) needs about [\d.]+ TiB of memory "
            r"\(2,000,000,000 frames of 18 agents held in memory\)",
        ),
        (
            lambda: stream_episode("mingle", seed=1, duration=1e9),
            r"would take about 10 days on this machine \(2,000,000,000 frames of 18 agents\)",
        ),
        (
            lambda: sim.episode.episode_blocks("mingle", seed=1, dt=5e-324),
            r"needs about 1.6e\+04 EiB of memory \(the world's schedule of 4.61e\+18 control "
            r"steps per frame\)",
        ),
    ],
    ids=["tiny-dt", "held-forever", "streamed-forever", "smallest-dt"],
)
def test_the_library_refuses_what_can_never_fit_before_any_work(machine, no_work, call, match):
    refusal, peak = raised_peak(call, RequestTooLarge)
    assert re.search(match, str(refusal)), str(refusal)
    assert peak < REFUSAL_PEAK_BYTES


def test_write_episode_streams_in_row_groups_and_reads_back_whole(tmp_path, monkeypatch):
    monkeypatch.setattr(sim.episode, "STREAM_CHUNK_BYTES", 40_000)  # a few frames a chunk
    options = {"talk_duration": 8.0}
    done = []
    written = write_episode(
        "hri-conversation",
        tmp_path / "streamed.parquet",
        seed=3,
        duration=12.0,
        options=options,
        progress=done.append,
    )
    expected = simulate_episode("hri-conversation", seed=3, duration=12.0, options=options)
    assert sum(done) == written.frames == 24
    assert pq.ParquetFile(written.path).num_row_groups > 2
    read = read_parquet(written.path)
    assert list(read) == list(expected.dataset)
    assert dict(read.metadata) == dict(expected.dataset.metadata)
    assert (read.name, read.source) == (expected.dataset.name, expected.dataset.source)
    assert written.events == expected.events
    sizes = {}
    for frame in expected.dataset:
        for group in frame.groups or ():
            if len(group) >= 2:
                sizes[len(group)] = sizes.get(len(group), 0) + 1
    assert written.group_sizes == sizes
    assert sorted(p.name for p in tmp_path.iterdir()) == ["streamed.parquet"]  # no scratch left


def test_write_episode_streams_the_robots_view(tmp_path, monkeypatch):
    monkeypatch.setattr(sim.episode, "STREAM_CHUNK_BYTES", 40_000)
    kwargs = dict(seed=2, duration=10.0, view="robot", options={"robot": "watch", "players": 3})
    written = write_episode("word-improv", tmp_path / "seen.parquet", **kwargs)
    expected = simulate_episode("word-improv", **kwargs)
    assert list(read_parquet(written.path)) == list(expected.dataset)


def test_a_frame_spanning_many_steps_takes_fewer_rows_per_block(monkeypatch):
    kwargs = dict(seed=1, duration=6.0, rate=1.0, dt=0.001, decision_rate=10.0)
    whole = [truth for truth, _ in stream_episode("hri-passing", **kwargs)]
    monkeypatch.setattr(sim.episode, "SCHEDULE_BYTES", 2 * 8_000)  # two frames' steps a block
    blocked = [truth for truth, _ in stream_episode("hri-passing", **kwargs)]
    assert blocked == whole


# --------------------------------------------------------------------------------------------
# The generator sized before it runs


def test_generate_refuses_a_billion_episodes_before_any_work(machine, no_work, tmp_path):
    out = tmp_path / "huge"
    refusal, peak = raised_peak(
        lambda: generate_dataset("mingle", episodes=10**9, seed=1, out_dir=out, n_jobs=2),
        RequestTooLarge,
    )
    assert refusal.resource == "memory"
    assert re.fullmatch(
        r"1,000,000,000 episodes of mingle needs about [\d.]+ TiB of memory \(the dataset "
        r"card's entries for 1,000,000,000 episodes\), more than the 16 GiB of memory this "
        r"machine has available; ask for less \(fewer episodes, a shorter duration or a lower "
        r"rate\), fewer workers \(n_jobs\), or change the limit with max_memory SIZE \(e.g. "
        r"64G\)",
        str(refusal),
    ), str(refusal)
    assert peak < REFUSAL_PEAK_BYTES
    assert not out.exists()


def test_generate_memory_limit_and_disk(machine, no_work, tmp_path, monkeypatch):
    kwargs = dict(seed=1, out_dir=tmp_path / "d", n_jobs=1, duration=600.0)
    with pytest.raises(RequestTooLarge, match=r"more than the limit max_memory 100 MiB"):
        generate_dataset("mingle", episodes=2, max_memory=100 * 2**20, **kwargs)
    monkeypatch.setattr(sizing, "free_disk", lambda path: 2**20)
    with pytest.raises(
        RequestTooLarge,
        match=r"writes about [\d.]+ MiB \(2,400 frames of 18 agents\), more than the 1 MiB free",
    ):
        generate_dataset("mingle", episodes=2, **kwargs)
    with pytest.raises(ValueError, match=r"max_memory must be an int >= 1, got 0"):
        generate_dataset("mingle", episodes=2, max_memory=0, **kwargs)


def test_generate_command_names_its_flags(machine, tmp_path, capsys):
    argv = ["generate", "--scenario", "mingle", "--seed", "1", "--out", str(tmp_path / "g")]
    assert main([*argv, "--episodes", "1000000000", "--jobs", "2"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("reform-sim generate: error: 1,000,000,000 episodes of mingle needs ")
    assert (
        "(fewer --episodes, a shorter --duration or a lower --rate), fewer workers (--jobs)" in err
    )
    assert err.rstrip().endswith("or change the limit with --max-memory SIZE (e.g. 64G)")
    assert main([*argv, "--episodes", "2", "--max-memory", "lots"]) == 2
    assert "--max-memory: expected a size such as 8G, 512M or 1.5GiB, got 'lots'" in (
        capsys.readouterr().err
    )
    assert not (tmp_path / "g").exists()


def test_generate_small_run_is_unaffected(tmp_path):
    report = generate_quietly(
        "hri-passing", tmp_path / "small", episodes=2, seed=1, duration=3.0, max_memory=8 * GiB
    )
    assert report.frames == 12
    assert np.all([s.frames == 6 for s in report.shards])


def test_a_study_counting_episodes_is_refused_when_even_its_least_cost_is_too_long(capsys):
    sizing.check_episodes(1000, what="the study", flag="--episodes")  # about a minute: fine
    with pytest.raises(sizing.RequestTooLarge, match=r"the study would take at least 2.41 years"):
        sizing.check_episodes(10**9, what="the study", flag="--episodes")
    for argv in (
        ["calibrate", "--episodes", "1000000000"],
        ["experiment", "hri", "--episodes", "1000000000"],
    ):
        assert main([*argv, "--out", "/tmp/never-written"]) == 2
        err = capsys.readouterr().err
        assert "would take at least" in err and "(--episodes)" in err and err.count("\n") == 1


def _one_line(argv, capsys) -> str:
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err.strip()


def test_the_stress_test_is_sized_before_it_runs(machine, tmp_path, capsys, monkeypatch):
    out = tmp_path / "stress"
    # 100,000 test episodes of 18 people held to perturb: memory, naming the limit's flag.
    err = _one_line(["stress", "--episodes", 100_000, "--out", out], capsys)
    assert re.fullmatch(
        r"reform-sim stress: error: the stress test needs about 5\d\d GiB of memory \(100,000 "
        r"test episodes of 18 people held to perturb\), more than the 16 GiB of memory this "
        r"machine has available; ask for less \(fewer --episodes, fewer --axes or the small "
        r"--grid\), fewer workers \(--jobs\), or change the limit with --max-memory SIZE "
        r"\(e\.g\. 64G\)",
        err,
    ), err
    # Given the memory, it is the time: months, beyond the week a run may take.
    err = _one_line(["stress", "--episodes", 100_000, "--max-memory", "1T", "--out", out], capsys)
    assert "the stress test would take about " in err and "more than the 7 days" in err
    # Disk at --out.
    monkeypatch.setattr(sizing, "free_disk", lambda path: 2**20)
    err = _one_line(["stress", "--out", out], capsys)
    assert f"more than the 1 MiB free where --out {out} is" in err
    assert not out.exists()


@pytest.mark.parametrize("command", [["stress", "--episodes", 1000], ["experiment", "gcff"]])
def test_a_dry_run_states_the_estimate_and_runs_nothing(
    machine, command, salsa_dir, babble_dir, tmp_path, capsys
):
    out = tmp_path / "out"
    data = ["--data", f"salsa={salsa_dir}", "--data", f"babble={babble_dir}"]
    argv = command + (data if command[0] == "experiment" else []) + ["--out", out]
    assert main([str(a) for a in argv + ["--dry-run"]]) == 0
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].endswith("written (estimates, sim.sizing)"), lines
    assert "about " in lines[0] and list(tmp_path.iterdir()) == []
    # A request the run would refuse is refused the same way.
    err = _one_line(argv + ["--max-memory", "1K", "--dry-run"], capsys)
    assert "error: " in err and "--max-memory" in err


def test_the_stress_estimate_grows_with_its_request():
    def estimate(seeds, levels):
        return sizing.stress_estimate(
            seeds=seeds,
            frames=301,
            rate_hz=0.5,
            base_people=18,
            perturb_levels=levels,
            scene_agents=[(18, False), (19, True)],
            train_frames=1200,
            workers=2,
        )

    small, more_seeds, more_levels = estimate(5, 19), estimate(50, 19), estimate(5, 38)
    assert 9 < more_seeds.seconds / small.seconds < 10.1  # all but the training: x10
    assert more_levels.seconds > small.seconds
    assert small.memory < more_levels.memory < more_seeds.memory  # scores held; episodes held
    # What it holds: 5 episodes of 301 frames of 18 people, each frame sizing.frame_bytes.
    held = 5 * 301 * sizing.frame_bytes(18)
    assert more_seeds.memory - small.memory > 9 * held


def test_the_gcff_grid_search_is_sized_before_it_runs(
    machine, salsa_dir, babble_dir, tmp_path, capsys
):
    grid = ",".join(f"{0.1 + k * 1e-4:.4f}" for k in range(3000))
    err = _one_line(
        ["experiment", "gcff", "--data", f"salsa={salsa_dir}", "--data", f"babble={babble_dir}"]
        + ["--stride-grid", grid, "--mdl-grid", grid.replace("0.", "1."), "--out", tmp_path / "g"],
        capsys,
    )
    assert err.startswith(
        "reform-sim experiment: error: the GCFF comparison (3000 strides x 3000 mdl values tuned "
        "on 686 SALSA frames) would take about "
    ), err
    assert "ask for less (shorter --stride-grid or --mdl-grid)" in err
    assert list(tmp_path.iterdir()) == []
    estimate = sizing.gcff_tuning_estimate(settings=49, tuning_frames=686, scored_frames=0)
    assert estimate.seconds == pytest.approx(49 * 686 * sizing.SECONDS_PER_GCFF_FRAME)


def test_generate_states_its_estimate_once(machine, tmp_path, capsys):
    generate_dataset(
        "mingle", episodes=1, seed=1, out_dir=tmp_path / "d", n_jobs=1, duration=2.0, progress=True
    )
    err = capsys.readouterr().err
    assert err.count("1 episode of mingle: about ") == 1
    assert re.search(
        r"1 episode of mingle: about [\d.]+ s on this machine"
        r"( \(busy: load [\d.]+ on \d+ CPUs\))?, [\d.]+ MiB of memory, "
        r"[\d.]+ KiB written \(estimates, sim.sizing\)",
        err,
    ), err
