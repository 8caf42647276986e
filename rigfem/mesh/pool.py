"""Meshes made ahead of the FE: a check names every part mesh it will need at its start, two
mesher processes make them while the FE solves the earlier parts, and :func:`mesh_part` takes a
finished one instead of meshing it again.

Measured (issue 26): meshing the standard ``final-cm`` parts one after another took 21.4 s,
with two mesher processes 14.8 s, and the FE of one part overlaps the meshing of the next.
Each job runs in a thread that only waits on its mesher process (:mod:`rigfem.mesh.worker`),
so the parent stays interruptible; :func:`cancel` ends every job not yet taken.  In a daemonic
process (a sweep worker, which may not have children) nothing is prefetched.
"""

from __future__ import annotations

import multiprocessing as mp
import threading
from concurrent.futures import Future

from rigfem.settings import MeshSettings

__all__ = ["WORKERS", "prefetch", "take", "cancel"]

#: mesher processes at a time (each holds one gmsh model; the FE runs beside them)
WORKERS = 2

_slots = threading.BoundedSemaphore(WORKERS)
_jobs: dict[str, tuple[Future, threading.Event]] = {}
_lock = threading.Lock()


def _run(fut: Future, stop: threading.Event, part, settings: MeshSettings, key: str, inputs: dict) -> None:
    from rigfem.mesh.mesher import make_mesh

    with _slots:
        if stop.is_set() or not fut.set_running_or_notify_cancel():
            return
        try:
            fut.set_result(make_mesh(part, settings, key, inputs, cancel=stop))
        except BaseException as exc:  # noqa: BLE001 - raised again where the mesh is taken
            fut.set_exception(exc)


def prefetch(jobs: list[tuple]) -> int:
    """Start meshing every (part, MeshSettings) of ``jobs`` not in the mesh cache, at most
    :data:`WORKERS` at a time, in the order given; returns how many were started.  Jobs of an
    earlier call that were never taken (a check that stopped early) are cancelled first."""
    from rigfem.mesh.mesher import mesh_folder, mesh_inputs

    cancel()
    if mp.current_process().daemon:
        return 0
    started = 0
    for part, settings in jobs:
        key, inputs = mesh_inputs(part, settings)
        with _lock:
            if key in _jobs or mesh_folder(part, key).exists():  # mesh_part verifies a cached entry
                continue
            fut, stop = Future(), threading.Event()
            _jobs[key] = (fut, stop)
        threading.Thread(target=_run, args=(fut, stop, part, settings, key, inputs), daemon=True,
                         name=f"rigfem-prefetch-{part.name}").start()
        started += 1
    return started


def take(key: str):
    """The prefetched mesh of cache key ``key`` (waiting for it), or None if it was not asked
    for; an interruption while waiting cancels every job."""
    with _lock:
        job = _jobs.pop(key, None)
    if job is None:
        return None
    try:
        return job[0].result()
    except BaseException:
        cancel()
        raise


def cancel() -> None:
    """End every prefetch job not yet taken (their mesher processes are killed)."""
    with _lock:
        jobs = list(_jobs.values())
        _jobs.clear()
    for fut, stop in jobs:
        stop.set()
        fut.cancel()
