"""gmsh in a child process: the parent waits interruptibly and ends the child on a signal.

gmsh holds the interpreter while it meshes (Ctrl-C was acted on minutes later); in a child
process the parent stays responsive, ends the child within a fraction of a second of SIGINT
or SIGTERM, and the memory gmsh took is returned to the system when the child exits.
Children come from a ``forkserver`` that has imported the mesher once, so a call costs a fork,
not a fresh interpreter; where the forkserver's socket cannot be made (a temporary folder whose
path leaves no room in a Unix socket's 107 bytes) they are spawned.
"""

from __future__ import annotations

import functools
import multiprocessing as mp
import os
import signal
import sys
import tempfile
import threading
from collections.abc import Callable
from typing import Any

from rigfem.errors import ComputeError

__all__ = ["call"]

#: how often the parent looks at the child, s: the latency of an interruption
POLL_S = 0.05

_START = threading.Lock()
#: the longest Unix socket path (Linux sun_path, 108 bytes with its NUL), and what multiprocessing
#: adds to the temporary folder for the forkserver's (``/pymp-XXXXXXXX/listener-XXXXXXXX``)
SOCKET_PATH_MAX, SOCKET_SUFFIX = 107, 33


@functools.lru_cache(maxsize=None)
def _context() -> mp.context.BaseContext:
    if len(os.fsencode(tempfile.gettempdir())) + SOCKET_SUFFIX > SOCKET_PATH_MAX:
        return mp.get_context("spawn")
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["rigfem.mesh.mesher"])
    return ctx


def _rigfem_env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if k.startswith("RIGFEM_")}


def _child(conn, fn: Callable, args: tuple, env: dict[str, str]) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides, and ends this process
    # the parent's rigfem settings as they are now (the forkserver has those of its start)
    for k in set(_rigfem_env()) - set(env):
        del os.environ[k]
    os.environ.update(env)
    try:
        result = (True, fn(*args))
    except BaseException as exc:  # noqa: BLE001 - every failure travels back to the parent
        result = (False, exc)
    try:
        conn.send(result)
    except Exception as exc:  # noqa: BLE001 - an exception that does not pickle
        conn.send((False, ComputeError(f"{type(result[1]).__name__}: {result[1]} ({exc})")))
    conn.close()


def _start(proc) -> None:
    """Start ``proc`` without running the caller's script again in it: multiprocessing imports
    the main script in a child, and a script calling rigfem without a ``__main__`` guard would
    then run twice."""
    with _START:  # two threads (rigfem.mesh.pool) must not interleave the hiding and the restoring
        main = sys.modules["__main__"]
        path = main.__dict__.pop("__file__", None)
        try:
            proc.start()
        finally:
            if path is not None:
                main.__file__ = path


def call(fn: Callable, *args: Any, cancel: threading.Event | None = None, what: str = "mesher") -> Any:
    """``fn(*args)`` in a child process; its exception is raised here.  KeyboardInterrupt or any
    exception raised in the parent while it waits (a signal handler's) kills the child first,
    and so does ``cancel`` being set (a caller in another thread: :mod:`rigfem.mesh.pool`).
    ``what`` names the child in its process name and errors.  In a daemonic process (which may
    not have children) ``fn`` runs in this process."""
    if mp.current_process().daemon:
        return fn(*args)
    ctx = _context()
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, fn, args, _rigfem_env()), daemon=True, name=f"rigfem-{what}")
    _start(proc)
    send.close()
    try:
        while not recv.poll(POLL_S):
            if cancel is not None and cancel.is_set():
                raise ComputeError(f"{what} cancelled")
            if not proc.is_alive() and not recv.poll(0):
                raise ComputeError(f"the {what} process ended without a result (exit code {proc.exitcode}; "
                                   f"out of memory?)")
        ok, value = recv.recv()
    except EOFError:
        raise ComputeError(f"the {what} process ended without a result (exit code {proc.exitcode})") from None
    finally:
        if proc.is_alive():
            proc.kill()
        proc.join()
        recv.close()
    if ok:
        return value
    raise value
