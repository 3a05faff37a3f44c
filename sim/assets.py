"""The one way to find the MJCF models shipped in the ``assets`` package.

Models are looked up by name (the file name without ``.xml``) through ``importlib.resources``,
so they are found in a source checkout and in a non-editable install alike.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

ASSET_PACKAGE = "assets"
PERSON_ASSET = "person"
ROBOT_ASSET = "robot"


def asset_names() -> tuple[str, ...]:
    """Names of the shipped models (file names without ``.xml``), sorted."""
    root = resources.files(ASSET_PACKAGE)
    return tuple(sorted(p.name[: -len(".xml")] for p in root.iterdir() if p.name.endswith(".xml")))


def asset_xml(name: str) -> str:
    """The MJCF text of the shipped model ``name``.

    Raises:
        ValueError: if no model of that name ships with the package.
    """
    resource = resources.files(ASSET_PACKAGE) / f"{name}.xml"
    if not isinstance(name, str) or not name or not resource.is_file():
        raise ValueError(f"unknown asset {name!r}: expected one of {list(asset_names())}")
    return resource.read_text(encoding="utf-8")


def asset_path(name: str) -> Path:
    """File-system path of the shipped model ``name`` (for tools that want a file).

    Raises:
        ValueError: if no model of that name ships with the package.
    """
    asset_xml(name)  # validates the name
    return Path(str(resources.files(ASSET_PACKAGE) / f"{name}.xml"))
