"""Where the compiled motion kernel is cached: beside the code when that folder can be written,
else in a folder of this user's under the system's temporary folder.

Numba caches compiled functions (``cache=True``) in the package's ``__pycache__``, else in the
user's cache folder; an installation read-only to its user with no writable home (a shared
install, a container running as ``nobody``) would otherwise fail at import with "cannot cache
function". `NUMBA_CACHE_DIR` set by the user is left alone.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numba

__all__ = ["use_a_writable_cache"]


def _writable(folder: Path) -> bool:
    while not folder.exists():
        folder = folder.parent
    return os.access(folder, os.W_OK)


def use_a_writable_cache() -> None:
    """Points numba's cache at a writable folder when neither the package's ``__pycache__`` nor
    the user's home can take it (called before the kernel's functions are compiled)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    here = Path(__file__).resolve().parent / "__pycache__"
    home = Path(os.path.expanduser("~"))
    if _writable(here) or (str(home) != "~" and _writable(home)):
        return
    folder = Path(tempfile.gettempdir()) / f"reform-sim-numba-{os.getuid()}"
    folder.mkdir(mode=0o700, exist_ok=True)
    info = folder.lstat()
    if folder.is_symlink() or info.st_uid != os.getuid() or info.st_mode & 0o077:
        # Someone else's folder (or one others may write in): the cache is code, so never
        # load it from there; a fresh private folder instead, compiled anew.
        folder = Path(tempfile.mkdtemp(prefix="reform-sim-numba-"))
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    numba.config.CACHE_DIR = str(folder)
