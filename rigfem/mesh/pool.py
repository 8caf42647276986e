"""Work started ahead of its use, at most :data:`WORKERS` jobs at a time, each in a thread that
only waits on a child process (:func:`rigfem.mesh.worker.call`): the parent stays interruptible.

:func:`rigfem.mesh.mesher.prefetch` submits a check's part meshes here so two mesher processes
make them while the FE solves the earlier parts (measured in issue 26: meshing the standard
``final-cm`` parts one after another 21.4 s, with two processes 14.8 s); ``mesh_part`` then
:func:`take` s a finished mesh.  :func:`cancel` ends every job not yet taken.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

__all__ = ["WORKERS", "submit", "state", "take", "cancel"]

#: jobs at a time (each a mesher process holding one gmsh model; the FE runs beside them)
WORKERS = 2

_slots = threading.BoundedSemaphore(WORKERS)
_jobs: dict[str, tuple[Future, threading.Event]] = {}
_lock = threading.Lock()


def _run(fut: Future, stop: threading.Event, fn: Callable[[threading.Event], Any]) -> None:
    with _slots:
        if stop.is_set() or not fut.set_running_or_notify_cancel():
            return
        try:
            fut.set_result(fn(stop))
        except BaseException as exc:  # noqa: BLE001 - raised again where the result is taken
            fut.set_exception(exc)


def submit(key: str, fn: Callable[[threading.Event], Any]) -> bool:
    """Start ``fn(stop)`` under ``key`` unless a job of that key is pending; ``stop`` is set when
    the job is cancelled (``fn`` must then end its child).  True if it was started."""
    with _lock:
        if key in _jobs:
            return False
        fut, stop = Future(), threading.Event()
        _jobs[key] = (fut, stop)
    threading.Thread(target=_run, args=(fut, stop, fn), daemon=True, name=f"rigfem-pool-{key}").start()
    return True


def state(key: str) -> str:
    """'done' (its result or exception ready to take), 'pending' (queued or running) or 'none'
    (no job ``key``)."""
    with _lock:
        job = _jobs.get(key)
    return "none" if job is None else "done" if job[0].done() else "pending"


def take(key: str) -> Any:
    """The result of the job ``key`` (waiting for it; its exception is raised here), or None if
    there is no such job.  An interruption while waiting cancels every job."""
    with _lock:
        job = _jobs.pop(key, None)
    if job is None:
        return None
    try:
        return job[0].result()
    except BaseException:
        cancel()
        raise


def cancel(spare: frozenset[str] = frozenset()) -> list[Future]:
    """End every job not yet taken but those of the keys ``spare``: queued ones never start,
    running ones see their ``stop`` set.  Returns their futures (done once each job has ended its
    child)."""
    with _lock:
        jobs = [_jobs.pop(k) for k in list(_jobs) if k not in spare]
    for fut, stop in jobs:
        stop.set()
        fut.cancel()
    return [fut for fut, _ in jobs]
