"""Format detection (one format per folder, else the caller names it) and DataFormatError."""

from __future__ import annotations

import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from dataset_refusals import assert_refused_by_each

from reform import DataFormatError, Dataset, Frame
from reform.datasets import _walk as walk
from reform.datasets import detect_format, load_dataset, resolve, write_parquet


def _salsa_and_babble(salsa_dir: Path, babble_dir: Path, folder: Path) -> Path:
    """A folder holding the first lines of SALSA's files and of Babble's."""
    folder.mkdir()
    for source, name, lines in (
        (salsa_dir, "features.txt", 3),
        (salsa_dir, "group_names.txt", 3),
        (babble_dir, "Motion-capture-data.csv", 21),
    ):
        head = (source / name).read_text().splitlines()[:lines]
        (folder / name).write_text("".join(line + "\n" for line in head))
    (folder / "annotated-frames.csv").write_text("16,{[1 2 3 4 5 6 7]}\n")
    return folder


def test_a_folder_of_two_formats_is_refused(salsa_dir, babble_dir, tmp_path):
    folder = _salsa_and_babble(salsa_dir, babble_dir, tmp_path / "both")
    message = (
        r"both: expected the files of one dataset format, found salsa \(features.txt, "
        r"group_names.txt\); babble \(Motion-capture-data.csv\); name the format to read: "
        r"format='salsa' or format='babble' \(--format on the command line\)"
    )
    assert_refused_by_each((detect_format, load_dataset), folder, message)
    assert load_dataset(folder, format="salsa").name == "both"  # named after its folder
    assert len(load_dataset(folder, format="babble")) == 20


def test_a_parquet_file_beside_salsa_is_ambiguous(salsa_dir, salsa_dataset, tmp_path):
    folder = tmp_path / "salsa"
    folder.mkdir()
    for name in ("features.txt", "group_names.txt"):
        (folder / name).write_bytes((salsa_dir / name).read_bytes())
    assert detect_format(folder) == "salsa"
    write_parquet(salsa_dataset, folder / "export" / "salsa.parquet")
    with pytest.raises(DataFormatError, match=r"format='salsa' or format='parquet'"):
        load_dataset(folder)
    assert load_dataset(folder, format="parquet").frames == salsa_dataset.frames


def test_data_format_error_survives_pickling():
    # Errors raised in worker processes travel back pickled.
    error = DataFormatError("a.txt", "line 1", "x", "a number", "'q'", hint="fix it")
    back = pickle.loads(pickle.dumps(error))
    assert (
        str(back) == str(error) == "a.txt: line 1: field 'x': expected a number, found 'q'; fix it"
    )
    assert (back.path, back.where, back.field, back.found) == (Path("a.txt"), "line 1", "x", "'q'")


def _tree(root: Path, *, folders: int, parquet_depth: int | None = None) -> Path:
    """``folders`` empty folders under ``root``, and a Parquet file ``parquet_depth`` levels
    down when given."""
    for k in range(folders):
        (root / f"d{k:04d}").mkdir(parents=True)
    if parquet_depth is not None:
        deep = root.joinpath(*[f"level{k}" for k in range(parquet_depth)])
        deep.mkdir(parents=True, exist_ok=True)
        frame = Frame(ids=[1], position=[[0.0, 0.0]], yaw=[0.0])
        write_parquet(Dataset(frames=(frame,), name="deep"), deep / "x.parquet")
    return root


def test_detection_looks_within_bounds_and_says_so(tmp_path, monkeypatch):
    monkeypatch.setattr(walk, "MAX_ENTRIES", 50)
    assert detect_format(_tree(tmp_path / "near", folders=10, parquet_depth=4)) == "parquet"
    with pytest.raises(DataFormatError, match=r"at most 4 levels down\), found none of them"):
        detect_format(_tree(tmp_path / "deep", folders=10, parquet_depth=5))
    huge = _tree(tmp_path / "huge", folders=60, parquet_depth=1)
    with pytest.raises(DataFormatError) as caught:
        detect_format(huge)
    assert str(caught.value) == (
        f"{huge}: expected a dataset folder (a search for *.parquet files at most 4 levels down "
        "looks at 50 entries at most), found more than 50 entries; name the dataset's own "
        "folder, or a file"
    )
    # Named as Parquet, the folder is read no further than the bound either.
    with pytest.raises(DataFormatError, match=r"found more than 50 entries"):
        load_dataset(huge, format="parquet")
    # A link to a folder is not followed (a loop would never end).
    loop = tmp_path / "loop"
    loop.mkdir()
    (loop / "self").symlink_to(loop)
    with pytest.raises(DataFormatError, match="found none of them"):
        detect_format(loop)


def test_data_info_of_the_root_folder_is_one_bounded_line():
    """``reform-sim data info /``: the whole file system is not walked; one line, exit 2."""
    process = subprocess.run(
        [sys.executable, "-m", "sim.cli", "data", "info", "--data", "/"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert process.returncode == 2, process.stderr
    lines = process.stderr.strip().splitlines()
    assert len(lines) == 1, process.stderr
    assert lines[0].startswith("reform-sim data: error: /: expected a"), lines[0]
    assert "found more than 100,000 entries" in lines[0] or "found none of them" in lines[0]


def _without_permission_override() -> list[str]:
    """The command prefix under which a file of mode 000 cannot be read: none for a user, and
    for root (who reads anything) setpriv without the permission-override capabilities."""
    if os.geteuid() != 0:
        return []
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        pytest.skip("running as root without setpriv: permissions cannot be denied")
    caps = "-dac_override,-dac_read_search"
    return [setpriv, f"--inh-caps={caps}", f"--bounding-set={caps}"]


def test_an_unreadable_folder_is_one_data_format_error_from_every_entry_point(tmp_path, salsa_dir):
    folder = Path(shutil.copytree(salsa_dir, tmp_path / "salsa"))
    folder.chmod(0)
    code = (
        "import sys\n"
        "from reform.datasets import detect_format, load_dante, load_dataset, read_parquet\n"
        "from reform import DataFormatError\n"
        "for f in (detect_format, load_dataset, load_dante, read_parquet):\n"
        "    for path in (sys.argv[1], sys.argv[1] + '/features.txt'):\n"
        "        try:\n"
        "            f(path)\n"
        "        except DataFormatError as exc:\n"
        "            print(f.__name__, str(exc))\n"
    )
    try:
        out = subprocess.run(
            [*_without_permission_override(), sys.executable, "-c", code, str(folder)],
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        folder.chmod(0o755)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert len(lines) == 8, out.stdout
    assert all("no permission to read it" in line and str(folder) in line for line in lines), lines


def test_a_generated_folder_may_hold_more_entries_than_the_bound(tmp_path, monkeypatch):
    """A card listing its shards vouches for a folder that large: its episodes are read even
    past the bound a folder of unknown files is held to."""
    from sim.generate import generate_dataset

    folder = tmp_path / "gen"
    generate_dataset(
        "mingle", episodes=3, seed=1, out_dir=folder, n_jobs=1, duration=1.0, progress=False
    )
    entries = sum(1 for _ in folder.rglob("*"))
    monkeypatch.setattr(walk, "MAX_ENTRIES", entries - 2)
    assert len(load_dataset(folder).sequences()) == 3
    (folder / "dataset.json").unlink()  # without the card: the bound holds
    with pytest.raises(DataFormatError, match=rf"found more than {entries - 2} entries"):
        load_dataset(folder, format="parquet")


def test_a_format_file_that_is_no_file_is_named_not_just_none_of_the_formats(tmp_path):
    folder = tmp_path / "set"
    folder.mkdir()
    (folder / "features.mat").mkdir()
    (folder / "Motion-capture-data.csv").symlink_to("Motion-capture-data.csv")  # a loop
    with pytest.raises(DataFormatError) as caught:
        detect_format(folder)
    assert str(caught.value).endswith(
        "found none of them: Motion-capture-data.csv is a symbolic link loop, features.mat is a "
        "folder"
    )
    # Given as the dataset itself, a link that leads nowhere is said so, not taken for a name.
    with pytest.raises(FileNotFoundError) as caught:
        resolve(folder / "Motion-capture-data.csv")
    assert str(caught.value) == (
        f"{folder / 'Motion-capture-data.csv'}: expected a dataset file or folder, found a "
        "symbolic link loop"
    )
