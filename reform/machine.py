"""What this machine can hold: its memory available now and in all (Linux ``/proc/meminfo``, the
POSIX page counts elsewhere). The loaders size a file against it before reading; `sim.sizing`
sizes whole runs against it."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["UNITS", "available_memory", "format_size", "total_memory"]

UNITS = ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB")  # binary units of sizes, in order

_MEMINFO = Path("/proc/meminfo")


def _meminfo() -> dict[str, int]:
    """``/proc/meminfo`` in bytes (empty where there is none)."""
    try:
        text = _MEMINFO.read_text()
    except OSError:
        return {}
    values = {}
    for line in text.splitlines():
        name, _, rest = line.partition(":")
        fields = rest.split()
        if fields and fields[0].isdigit():
            values[name] = int(fields[0]) * (1024 if fields[1:] == ["kB"] else 1)
    return values


def _sysconf(name: str) -> int:
    try:
        return int(os.sysconf(name)) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return 0


def available_memory() -> int:
    """Bytes of memory a new allocation can have without swapping (Linux ``MemAvailable``; the
    free physical pages elsewhere)."""
    info = _meminfo()
    if "MemAvailable" in info:
        return info["MemAvailable"]
    return _sysconf("SC_AVPHYS_PAGES")


def total_memory() -> int:
    """Bytes of physical memory and swap together: no request beyond this can be held."""
    info = _meminfo()
    if "MemTotal" in info:
        return info["MemTotal"] + info.get("SwapTotal", 0)
    return _sysconf("SC_PHYS_PAGES")


def format_size(size: float) -> str:
    """``3.6 GiB``: a size in bytes, in the largest binary unit below it."""
    size = float(size)
    for unit in UNITS:
        if abs(size) < 1024.0 or unit == UNITS[-1]:
            break
        size /= 1024.0
    if unit == "B" or 999.5 <= abs(size) < 1024.0:  # 1010 KiB, not 1.01e+03 KiB
        return f"{size:.0f} {unit}"
    return f"{size:.3g} {unit}"
