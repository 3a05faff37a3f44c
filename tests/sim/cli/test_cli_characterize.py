"""``reform-sim characterize``: end to end on the real datasets and on Parquet files."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_errors import cli_error, cli_json, run_cli

from reform import Dataset, Frame
from reform.datasets import write_parquet
from sim.experiments.characterisation_report import format_calibration, format_characterisation


def test_characterize_salsa_and_babble_beside_the_paper(salsa_dir, babble_dir, tmp_path, capsys):
    out_json, out_md, notes = tmp_path / "c.json", tmp_path / "c.md", tmp_path / "notes.md"
    notes.write_text("Our numbers differ because of X.\n")
    result, out, err = cli_json(
        [
            "characterize",
            "--data",
            salsa_dir,
            babble_dir,
            "--compare-to",
            babble_dir,
            "--by-sequence",
            "--json",
            out_json,
            "--markdown",
            out_md,
            "--notes",
            notes,
        ],
        out_json,
        capsys,
    )
    assert result["schema_version"] == 1 and result["min_groups"] == 5
    assert result["command"].startswith("reform-sim characterize --data ")
    salsa, babble = result["datasets"]
    assert (salsa["name"], babble["name"]) == ("salsa", "babble")
    assert salsa["annotated_frames"] == 1143 and babble["annotated_frames"] == 99
    assert (
        salsa["paper"]["tightness_m"]["7"] == 0.93 and babble["paper"]["symmetry_deg"]["3"] == 234
    )
    assert [e["size"] for e in babble["by_size"]] == [2, 3, 4, 5, 6, 7]
    assert babble["anova"]["tightness"]["sizes"] == [2, 3, 4, 5, 6, 7]
    assert babble["anova"]["symmetry"]["sizes"] == [3, 4, 5, 6, 7]
    assert len(babble["tukey"]["tightness"]["pairs"]) == 15  # C(6, 2)
    # SALSA's size 12 (one group) is left out of the tests; size 8 (25 groups) is in.
    assert salsa["anova"]["tightness"]["sizes"] == [2, 3, 4, 5, 6, 7, 8]
    assert set(salsa["sequences"]) == {"session1", "session2"}
    assert "sequences" not in babble  # one sequence: nothing to split
    # Paper Tightness, SALSA: session 2 reproduces it (f2 .44, f3 .54 ... f7 .93) to 0.01 m.
    session2 = {e["size"]: e["tightness_mean_m"] for e in salsa["sequences"]["session2"]["by_size"]}
    for size, value in salsa["paper"]["tightness_m"].items():
        assert session2[int(size)] == pytest.approx(value, abs=0.01)
    # babble against babble is skipped: one comparison, SALSA's looser-than-Babble verdict.
    (comparison,) = result["comparisons"]
    assert (comparison["candidate"], comparison["reference"]) == ("salsa", "babble")
    assert comparison["within_tolerance"] is False and len(comparison["failures"]) == 6

    assert "salsa: 1,143 annotated frames" in out and "ours - paper" in out
    assert "Tukey's HSD, tightness" in out and "salsa against babble" in out
    markdown = out_md.read_text()
    assert markdown.startswith("# Characterisation of F-formations")
    assert result["command"] in markdown
    assert "| size | groups | Tightness (m) |" in markdown
    assert "+0.404\\*\\*\\*" in markdown  # Babble 7 vs 2: stars escaped, not emphasis
    assert markdown.rstrip().endswith("## Discussion\n\nOur numbers differ because of X.")
    # The tables rebuild from the saved JSON alone.
    assert format_characterisation(babble, style="text") in out
    assert format_calibration(comparison, style="text") in out


def _circle_frame(radius: float, sizes: tuple[int, ...], *, time: float) -> Frame:
    """Groups of the given sizes on circles of ``radius``, members facing the centre."""
    positions, yaws, groups = [], [], []
    for k, size in enumerate(sizes):
        angles = 2 * np.pi * np.arange(size) / size + 0.1 * time
        centre = np.array([6.0 * k, 0.0])
        positions.append(centre + radius * np.column_stack([np.cos(angles), np.sin(angles)]))
        yaws.append(np.angle(np.exp(1j * (angles + np.pi))))
        start = sum(sizes[:k])
        groups.append(tuple(range(start, start + size)))
    return Frame(
        ids=np.arange(sum(sizes)),
        position=np.concatenate(positions),
        yaw=np.concatenate(yaws),
        groups=tuple(groups),
        time=time,
        sequence="episode",
    )


def _parquet(path, name: str, radius: float, sizes=(2, 3, 4), n_frames: int = 6):
    frames = tuple(_circle_frame(radius, sizes, time=float(t)) for t in range(n_frames))
    return write_parquet(Dataset(frames=frames, name=name, source="test"), path)


def test_check_fails_only_when_tightness_misses_the_tolerance(tmp_path, capsys):
    reference = _parquet(tmp_path / "ref.parquet", "reference", 0.8)
    close = _parquet(tmp_path / "close.parquet", "close", 0.85)
    far = _parquet(tmp_path / "far.parquet", "far", 1.0)
    # On a circle the Tightness is the radius: close is 0.05 m off, far 0.2 m.
    status, out, err = run_cli(
        ["characterize", "--data", close, "--compare-to", reference, "--check"], capsys
    )
    assert status == 0, err
    assert "close against reference" in out and "for every size the reference holds" in out
    check_far = ["characterize", "--data", far, "--compare-to", reference, "--check"]
    status, out, err = run_cli([*check_far, "--json", tmp_path / "f.json"], capsys)
    assert status == 1
    assert "misses the tolerance" in err
    assert "size 2: mean Tightness 1.000 m vs reference 0.800 m (difference +0.200 m" in out
    (comparison,) = json.loads((tmp_path / "f.json").read_text())["comparisons"]
    assert [e["tightness_difference_m"] for e in comparison["by_size"]] == pytest.approx([0.2] * 3)
    # A wider tolerance lets it pass.
    status, _, err = run_cli([*check_far, "--tolerance", "0.25"], capsys)
    assert status == 0, err


def test_one_group_size_prints_no_tests(tmp_path, capsys):
    pairs = _parquet(tmp_path / "pairs.parquet", "pairs", 0.5, sizes=(2, 2))
    status, out, err = run_cli(["characterize", "--data", pairs], capsys)
    assert status == 0, err
    assert "fewer than 2 with >= 5 groups" in out
    assert "Tukey" not in out


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--notes", "n.md"], "--notes is appended to the Markdown report: give --out DIR"),
        (["--min-groups", "0"], "--min-groups must be >= 1, got 0"),
        (["--tolerance", "-1"], "--tolerance must be a positive number of metres, got -1"),
    ],
)
def test_bad_options_are_refused(tmp_path, capsys, extra, message):
    data = _parquet(tmp_path / "d.parquet", "d", 0.5)
    status, _, err = run_cli(["characterize", "--data", data, *extra], capsys)
    assert status == 2
    assert message in err


def test_unannotated_data_and_missing_paths_are_refused(tmp_path, capsys):
    frame = _circle_frame(0.5, (2,), time=0.0).replace(groups=None)
    path = write_parquet(Dataset(frames=(frame,), name="raw"), tmp_path / "raw.parquet")
    status, _, err = run_cli(["characterize", "--data", path], capsys)
    assert status == 2 and "no annotated frames, nothing to characterise" in err
    status, _, err = run_cli(["characterize", "--data", tmp_path / "nowhere.parquet"], capsys)
    assert status == 2 and "nowhere.parquet" in err


def test_a_dataset_given_twice_is_refused_before_any_is_read(
    salsa_dir, babble_dir, tmp_path, capsys, monkeypatch
):
    data = _parquet(tmp_path / "d.parquet", "d", 0.5)
    monkeypatch.chdir(tmp_path)
    for first, again, dataset in (
        ("salsa", "salsa", salsa_dir.resolve()),
        (data, "./d.parquet", data),
        ("d.parquet", "d.parquet", data),
    ):
        argv = ["characterize", "--data", first, babble_dir, "--data", again]
        assert cli_error([*argv, "--out", tmp_path / "out"], capsys) == (
            f"reform-sim characterize: error: --data {again}: dataset {dataset} is given "
            f"twice (also as --data {first}); give each dataset once"
        )
    assert not (tmp_path / "out").exists()
