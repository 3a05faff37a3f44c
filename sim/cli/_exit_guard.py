"""``os._exit`` in someone else's code while a command runs: one line and status 2, not silence.

``os._exit`` ends the process at once, past every ``except``, ``finally`` and ``atexit``: a plugin
detector whose module, factory or ``predict`` calls it would end ``detect`` with status 0 and no
output, as if it had succeeded. While a command runs, this process's ``os._exit`` is guarded
(:func:`os_exit_reported`): called in the main thread it raises `ProcessExit`, a SystemExit, which
the detector's caller reports as the plugin's failure in one line, as it does a ``sys.exit``;
called in another thread it writes that line itself and ends the process with status 2. A forked
child (another process id) exits as it asks: ``os._exit`` is how a fork ends.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
from collections.abc import Iterator
from typing import NoReturn

__all__ = ["EXIT_STATUS", "ProcessExit", "os_exit_reported"]

EXIT_STATUS = 2  # exit status of a command that someone's os._exit ended


class ProcessExit(SystemExit):
    """``os._exit(status)`` called by code a command runs, in its main thread; the message
    names the status and where it was called (``"os._exit(0) called at plugin.py:3"``)."""


@contextlib.contextmanager
def os_exit_reported(command: str) -> Iterator[None]:
    """Within: ``os._exit`` in this process is reported (see the module notes).

    Args:
        command: the command's name, for the line written when another thread calls it.
    """
    real = os._exit
    owner = os.getpid()

    def guarded(status: int) -> NoReturn:
        if os.getpid() != owner:  # a forked child ending
            real(status)
        caller = sys._getframe(1)
        what = f"os._exit({status}) called at {caller.f_code.co_filename}:{caller.f_lineno}"
        if threading.current_thread() is threading.main_thread():
            raise ProcessExit(what)
        with contextlib.suppress(Exception):
            name = threading.current_thread().name
            sys.stderr.write(
                f"reform-sim {command}: error: {what} (thread {name}) before the command finished\n"
            )
            sys.stderr.flush()
        real(EXIT_STATUS)

    os._exit = guarded
    try:
        yield
    finally:
        if os._exit is guarded:
            os._exit = real
