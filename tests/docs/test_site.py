"""The documentation site builds in strict mode, and strict mode catches what it should."""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]
API_PACKAGES = ("reform", "reform.datasets", "scenarios", "sim", "sim.envs")


def _mkdocs_build(config: Path, site: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1", MPLBACKEND="Agg")
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "mkdocs",
            "build",
            "--strict",
            "--config-file",
            str(config),
            "--site-dir",
            str(site),
        ],
        cwd=config.parent,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site, built from mkdocs.yml in strict mode (a warning fails the build)."""
    site = tmp_path_factory.mktemp("site")
    done = _mkdocs_build(REPO / "mkdocs.yml", site)
    assert done.returncode == 0, f"mkdocs build --strict failed:\n{done.stderr[-6000:]}"
    return site


def _nav_pages(nav) -> list[str]:
    pages = []
    for entry in nav:
        value = next(iter(entry.values())) if isinstance(entry, dict) else entry
        pages += _nav_pages(value) if isinstance(value, list) else [value]
    return pages


def _html(site: Path, page: str) -> str:
    return (
        (site / page.removesuffix(".md") / "index.html").read_text(encoding="utf-8")
        if (page != "index.md")
        else (site / "index.html").read_text(encoding="utf-8")
    )


def test_every_page_of_the_nav_is_built(site):
    nav = _nav_pages(yaml.safe_load((REPO / "mkdocs.yml").read_text())["nav"])
    assert len(nav) >= 40
    for page in nav:
        assert "<h1" in _html(site, page), page


def test_the_command_reference_documents_every_subcommand_from_its_parser(site):
    from sim.cli import build_parser

    page = _html(site, "reference/cli.md")

    def walk(parser: argparse.ArgumentParser, prog: str) -> None:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    sub.format_help()  # adds its arguments
                    full = f"{prog} {name}"
                    if sub.prog.split()[-1] != name:  # an alias
                        continue
                    anchor = full.replace(" ", "-")
                    assert f'id="{anchor}"' in page, f"no section for {full}"
                    section = page[page.index(f'id="{anchor}"') :]
                    for option in sub._actions:
                        for flag in option.option_strings:
                            if flag not in ("-h", "--help") and option.help != argparse.SUPPRESS:
                                assert f"<code>{flag}" in section, f"{full}: {flag} missing"
                    walk(sub, full)

    walk(build_parser(), "reform-sim")


@pytest.mark.parametrize("package", API_PACKAGES)
def test_the_api_reference_documents_every_public_name(site, package):
    import importlib

    module = importlib.import_module(package)
    pages = "".join(_html(site, f"reference/api/{p}.md") for p in API_PACKAGES)
    own = _html(site, f"reference/api/{package}.md")
    for name in module.__all__:
        if name.startswith("__"):
            continue
        # Each name has its heading on its package's page, or a link to the page that has it.
        assert re.search(rf">\s*{re.escape(f'{package}.{name}')}\s*<", own), name
        ids = re.findall(rf'id="([\w.]+\.{re.escape(name)})"', pages)
        assert ids, f"{package}.{name} is documented nowhere"


def test_strict_mode_fails_on_a_broken_link_and_a_missing_reference(tmp_path):
    project = yaml.safe_load((REPO / "mkdocs.yml").read_text())
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "index.md").write_text("# Home\n\nSee [the guide](guide.md).\n")
    (docs / "other.md").write_text("# Other\n\nSee [`Frame`][reform.frame.NoSuchThing].\n")
    config = {
        "site_name": "t",
        "strict": True,
        "validation": project["validation"],
        "plugins": ["autorefs"],
        "nav": ["index.md", "other.md"],
    }
    (tmp_path / "mkdocs.yml").write_text(yaml.safe_dump(config))
    done = _mkdocs_build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert done.returncode != 0
    assert "guide.md" in done.stderr
    assert "reform.frame.NoSuchThing" in done.stderr
