"""The README is short and true, and CHANGELOG.md and CITATION.cff beside it are well formed."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import jsonschema
import yaml
from site_pages import blocks

REPO = Path(__file__).resolve().parents[2]
README = REPO / "README.md"
README_MAX_BYTES = 10_000  # the READMEs of Gymnasium, scikit-learn, MuJoCo and Rerun: under 10 KB
# The Citation File Format's schema, version 1.2.0 (citation-file-format, CC-BY-4.0), as shipped
# in the cffconvert 2.0.0 wheel (cffconvert/schemas/1.2.0/schema.json).
CFF_SCHEMA = Path(__file__).with_name("cff-1.2.0-schema.json")
CHANGE_KINDS = ("Added", "Changed", "Deprecated", "Removed", "Fixed", "Security")


def _version() -> str:
    return tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["version"]


def test_the_readme_is_short():
    assert README.stat().st_size < README_MAX_BYTES


def test_the_readme_opens_with_the_two_commands_and_the_makefile_has_them():
    first = blocks(README.read_text(encoding="utf-8"))[0]
    commands = [line.split("#")[0].strip() for line in first.code.strip().split("\n")]
    assert (first.language, commands) == ("bash", ["make demo", "make test"])
    makefile = (REPO / "Makefile").read_text()
    assert re.search(r"^demo:", makefile, re.M) and re.search(r"^test:", makefile, re.M)


def test_the_readme_python_example_runs(tmp_path):
    (example,) = [b for b in blocks(README.read_text(encoding="utf-8")) if b.language == "python"]
    assert len(example.code.strip().split("\n")) <= 12
    done = subprocess.run(
        [sys.executable, "-c", example.code],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert re.fullmatch(r"REFORM: F1 at T=2/3 \d\.\d\d\nGCFF: F1 at T=2/3 \d\.\d\d\n", done.stdout)


def test_every_link_of_the_readme_reaches_a_file_and_its_pages_are_in_the_site():
    text = README.read_text(encoding="utf-8")
    nav = (REPO / "mkdocs.yml").read_text()
    links = re.findall(r"\]\(([^)#\s]+)\)", text)
    local = [link for link in links if "://" not in link]
    assert len(local) >= 30
    for link in local:
        assert (REPO / link).exists(), f"README links to {link}, which is not there"
        if link.startswith("docs/") and link.endswith(".md"):
            assert link.removeprefix("docs/") in nav, f"{link} is not in the site's nav"


def test_the_changelog_keeps_a_changelog_and_lists_this_version():
    text = (REPO / "CHANGELOG.md").read_text(encoding="utf-8")
    assert text.startswith("# Changelog\n")
    assert "https://keepachangelog.com/en/1.1.0/" in text
    releases = re.findall(r"^## \[([^\]]+)\](?: - (.+))?$", text, re.M)
    assert releases and releases[0][0] in ("Unreleased", _version())
    assert _version() in [name for name, _ in releases]
    for name, date in releases:
        assert name == "Unreleased" or re.fullmatch(r"\d+\.\d+\.\d+", name), name
        assert name == "Unreleased" or re.fullmatch(r"\d{4}-\d{2}-\d{2}|Unreleased", date), date
    for kind in re.findall(r"^### (.+)$", text, re.M):
        assert kind in CHANGE_KINDS, kind


def test_the_citation_file_is_valid_cff_and_cites_the_software_and_the_paper():
    citation = yaml.safe_load((REPO / "CITATION.cff").read_text(encoding="utf-8"))
    jsonschema.Draft7Validator(json.loads(CFF_SCHEMA.read_text())).validate(citation)
    assert (citation["cff-version"], citation["type"]) == ("1.2.0", "software")
    assert str(citation["version"]) == _version()
    assert citation["license"] == "MIT"
    (paper,) = citation["references"]
    assert paper["title"] == "REFORM: Recognizing F-formations for Social Robots"
    assert [a["family-names"] for a in paper["authors"]] == [
        "Hedayati",
        "Muehlbradt",
        "Szafir",
        "Andrist",
    ]


def test_the_schema_check_refuses_a_broken_citation():
    broken = yaml.safe_load((REPO / "CITATION.cff").read_text(encoding="utf-8"))
    del broken["authors"]
    validator = jsonschema.Draft7Validator(json.loads(CFF_SCHEMA.read_text()))
    assert not validator.is_valid(broken)


def test_the_site_home_page_shows_the_readme_example():
    (readme,) = [b for b in blocks(README.read_text(encoding="utf-8")) if b.language == "python"]
    home = [b for b in blocks((REPO / "docs" / "index.md").read_text()) if b.language == "python"]
    assert [b.code for b in home] == [readme.code]
