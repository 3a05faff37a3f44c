"""Reading a file with a third-party parser in a child process, so that a hostile file cannot
take this process down.

scipy's MATLAB reader is compiled code; a corrupt ``.mat`` file can make it crash the process
(a segmentation fault, seen with four zero bytes in the right place) or ask for more memory than
the machine has. :func:`run_isolated` runs the reader in a forked child with an address-space
limit and returns what it returned; a crash or an exception in the child comes back as
:class:`IsolatedFailure`, which the loader turns into its one-line error. The child's result
travels back pickled through a pipe: it is this program's own child, holding only what the
reader built, so no file's bytes are ever unpickled. Where ``fork`` does not exist (Windows),
the reader runs in this process.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["MEMORY_HEADROOM_BYTES", "IsolatedFailure", "run_isolated"]

T = TypeVar("T")

# Address space the child may take beyond what this process already maps, bytes: far more than
# any public F-formation dataset needs (the largest .mat file is 2.9 MB), far less than a
# machine's memory, so that a file claiming a gigantic matrix fails as a MemoryError.
MEMORY_HEADROOM_BYTES = 4 * 2**30


class IsolatedFailure(Exception):
    """The reader failed in the child: ``kind`` is the exception's type name (or ``"crash"``),
    ``message`` what it said (or which signal ended the child)."""

    def __init__(self, kind: str, message: str) -> None:
        self.kind = kind
        self.message = message
        super().__init__(f"{kind}: {message}")


def _mapped_bytes() -> int:
    try:
        with open("/proc/self/statm") as handle:
            pages = int(handle.read().split()[0])
        return pages * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def _child(write: int, function: Callable[..., Any], args: tuple) -> None:
    try:
        import resource

        limit = _mapped_bytes() + MEMORY_HEADROOM_BYTES
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    except (ImportError, ValueError, OSError):
        pass
    too_big = (
        "MemoryError",
        f"more than the {MEMORY_HEADROOM_BYTES / 2**30:g} GiB of memory a file may take to read "
        "(a compressed bomb, or a matrix it claims too large)",
    )
    try:
        payload = ("ok", function(*args))
    except MemoryError:
        payload = ("error", *too_big)
    except BaseException as exc:  # everything the reader raises goes back to the parent
        payload = ("error", type(exc).__name__, str(exc))
    try:
        data = pickle.dumps(payload, protocol=pickle.HIGHEST_PROTOCOL)
    except MemoryError:
        data = pickle.dumps(("error", *too_big))
    except Exception as exc:
        data = pickle.dumps(("error", type(exc).__name__, f"result not transferable: {exc}"))
    with os.fdopen(write, "wb") as pipe:
        pipe.write(data)


def run_isolated(function: Callable[..., T], *args: Any) -> T:
    """``function(*args)`` computed in a forked child (or here, without ``fork``).

    Raises:
        IsolatedFailure: the function raised in the child, or the child died (a signal).
    """
    if not hasattr(os, "fork") or sys.platform == "emscripten":
        return function(*args)
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns into the caller's code
        os.close(read)
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            import faulthandler

            faulthandler.disable()  # a crash is reported by the parent, in one line
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 2)
            _child(write, function, args)
        finally:
            os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as pipe:
        data = pipe.read()
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        try:
            name = signal.Signals(number).name
        except ValueError:
            name = str(number)
        raise IsolatedFailure("crash", f"a file that crashed the reader (signal {name})")
    if not data:
        raise IsolatedFailure("crash", f"the reader exited with status {os.WEXITSTATUS(status)}")
    payload = pickle.loads(data)  # written by this program's own child (see the module notes)
    if payload[0] == "ok":
        return payload[1]
    raise IsolatedFailure(payload[1], payload[2])
