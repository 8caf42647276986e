"""Pictures and field files through the cache: each is a pure function of what it is drawn from.

Rendering a part's pictures costs seconds (pyvista and matplotlib); a warm check draws the same
pictures again from the same cached solution.  Each call below hashes everything its picture is
drawn from (the field arrays, the mesh, the titles and labels and the plotting libraries'
versions; the package's code is in every key) into the key of a verified cache entry
(:mod:`rigfem.cache`, kind ``pictures``), and a hit copies the stored files: byte for byte the
pictures a cold run drew, without pyvista.  A fallback picture (matplotlib, where no OpenGL
runs) is not stored: a machine that gains OpenGL draws the real one.  The VTU field files of a
cached solution (:func:`write_vtu`) and a cycle case's animation frames (:func:`write_frames`)
are stored the same way, keyed by the solution's entry and the load combinations.

The drawing code (matplotlib) is imported only where a picture is drawn, so a warm check, which
draws none, does not import it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import gc
import itertools
import json
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from rigfem.cache import Cache, Entry, resolve
from rigfem.memory import trim_heap
from rigfem.report.figures import PICTURES

_RESULT = "result.json"
#: numbers the calls of started_part_pictures (their jobs' keys in the pool)
_RUNS = itertools.count()


@functools.lru_cache(maxsize=None)
def _versions() -> dict[str, str]:
    """Versions of the plotting libraries (their output is part of what a picture is)."""
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for lib in ("matplotlib", "pyvista", "vtk", "numpy", "meshio"):
        try:
            out[lib] = version(lib)
        except PackageNotFoundError:
            out[lib] = "-"
    return out


def _full(kind: str, inputs: dict) -> dict:
    return {"kind": kind, **inputs, "libraries": _versions()}


def _lookup(kind: str, inputs: dict, folder: Path, cache: Cache) -> dict | None:
    """The stored result of a picture (its files copied into ``folder``), or None."""
    def load(entry: Entry) -> dict:
        stored = entry.json(_RESULT)
        for name in stored["files"]:
            entry.copy(name, folder / name)
        return stored["result"]

    return cache.get("pictures", _full(kind, inputs), load)


def cached(kind: str, inputs: dict, folder: Path, draw: Callable[[Path], tuple[dict, list[str]]],
           cache: Cache) -> dict:
    """``draw(folder)`` -> (result, file names it wrote in ``folder``), or the stored files copied
    into ``folder`` and the stored result when ``cache`` holds an entry of ``inputs``."""
    result = _lookup(kind, inputs, folder, cache)
    if result is not None:
        return result
    result, files = draw(folder)
    if result.get("renderer", "pyvista") == "pyvista":

        def write(tmp: Path) -> None:
            for name in files:
                (tmp / name).write_bytes((folder / name).read_bytes())
            (tmp / _RESULT).write_text(json.dumps({"files": files, "result": result}))

        cache.put("pictures", _full(kind, inputs), write)
    return result


def _part_inputs(r, c: np.ndarray, entry: dict, limit: float, label: str, allowable: str, zoom_mm: float = 30.0,
                 kinds: tuple[str, ...] = PICTURES, stem: str | None = None) -> dict:
    sol, fm = r.solution, r.solution.model.mesh
    groups = sorted(fm.surfaces)
    return {"fields": [sol.von_mises(c), sol.displacement(c), sol.loads(c)],
            "mesh": [fm.nodes, fm.elements, *(fm.surfaces[g] for g in groups)], "groups": groups,
            "n_vertices": fm.n_vertices, "case": r.case.name, "mode": r.mode,
            "crank_deg": float(r.case.rows[r.row]),
            "loads": [(ld.kind, ld.group) for ld in r.case.loads], "supports": r.case.supports,
            "entry": {**{k: entry.get(k) for k in ("peak_mpa", "utilisation_pct", "error_pct", "verdict", "band_mpa",
                                                   "band_pct_of_allowable")},
                      "mesh": {k: (entry.get("mesh") or {}).get(k) for k in ("level", "stopped")}},
            "limit": limit, "label": label, "allowable": allowable, "zoom_mm": zoom_mm, "kinds": list(kinds),
            "stem": stem or r.case.name}


def part_pictures(r, c: np.ndarray, entry: dict, limit: float, label: str, allowable: str,
                  folder: str | Path, zoom_mm: float = 30.0, kinds: tuple[str, ...] = PICTURES,
                  stem: str | None = None, cache: Cache | None = None) -> dict:
    """:func:`rigfem.report.pictures.part_pictures` through ``cache`` (same arguments, same result)."""

    def draw(d: Path) -> tuple[dict, list[str]]:
        from rigfem.report import pictures

        out = pictures.part_pictures(r, c, entry, limit, label, allowable, d, zoom_mm, kinds, stem)
        return out, list(out["files"].values())

    return cached("part", _part_inputs(r, c, entry, limit, label, allowable, zoom_mm, kinds, stem), Path(folder),
                  draw, resolve(cache))


def _one_combination(r, c: np.ndarray):
    """A copy of the case result ``r`` whose solution holds only the combination ``c``
    (:meth:`~rigfem.fe.solution.Solution.kept`): what its pictures are drawn from, a few MB to send
    to a child process instead of every unit solution.  Its pictures, and their cache key, are
    those of ``r`` at ``c``: the fields are the same numbers."""
    sol = r.solution
    model = dataclasses.replace(sol.model, mesh=dataclasses.replace(sol.model.mesh, cache={}), _K=None)
    one = dataclasses.replace(sol.kept(c[None]), model=model)
    return dataclasses.replace(r, solution=one, cycle_nodes=None, cycle_stress=None, frames={}, frame_loads={})


def _draw_all(jobs: list[tuple], cache: Cache) -> list[dict]:
    out = []
    for job in jobs:
        out.append(part_pictures(*job, cache=cache))
        gc.collect()  # the part's VTK objects and what they hold, before the next part is drawn
        trim_heap()
    return out


@contextlib.contextmanager
def started_part_pictures(jobs: list[tuple], cache: Cache, workers: int = 2) -> Iterator[Callable[[], list[dict]]]:
    """Start :func:`part_pictures` of every job (a tuple of its arguments); yields the function
    that waits for their results, in order.

    Pictures the cache holds are copied at once; the others, most of a cold report's time, are
    drawn in up to ``workers`` child processes (:func:`rigfem.mesh.worker.call`, started through
    :mod:`rigfem.mesh.pool`), each importing the drawing code once, while the caller writes the
    rest of the report.  In a process that may not have children (a daemonic one) they are drawn
    when waited for.  An exception in the block ends the children before it goes on."""
    import multiprocessing as mp

    from rigfem.mesh import pool
    from rigfem.mesh.worker import call

    done, todo = {}, []
    for i, (r, c, entry, limit, label, allowable, folder, *more) in enumerate(jobs):
        got = _lookup("part", _part_inputs(r, c, entry, limit, label, allowable, *more), Path(folder), cache)
        if got is None:
            todo.append(i)
        else:
            done[i] = got
    size = {i: len(jobs[i][0].solution.model.mesh.nodes) for i in todo}
    shares: list[list[int]] = [[] for _ in range(max(1, min(workers, len(todo))))]
    for i in sorted(todo, key=lambda i: -size[i]):  # the largest first, each to the lightest share
        min(shares, key=lambda sh: sum(size[j] for j in sh)).append(i)
    if not todo or mp.current_process().daemon:
        shares = []
    slim = [[(_one_combination(jobs[i][0], jobs[i][1]), *jobs[i][1:]) for i in share] for share in shares]
    run = next(_RUNS)  # keys of this call's own: an id() of a list could be a finished call's again
    keys = [(f"pictures-{run}-{share[0]}", share) for share in shares]

    def wait() -> list[dict]:
        for key, share in keys:
            done.update(zip(share, pool.take(key) or []))
        for i in todo:
            if i not in done:  # no children here, or a job cancelled: here
                done[i] = part_pictures(*jobs[i], cache=cache)
        return [done[i] for i in range(len(jobs))]

    try:
        for (key, _), part in zip(keys, slim):
            pool.submit(key, lambda stop, part=part: call(_draw_all, part, cache, cancel=stop, what="pictures"))
        yield wait
    except BaseException:
        for fut in pool.cancel():  # the children end before the caller removes their folder
            try:
                fut.exception(timeout=5.0)
            except BaseException:  # noqa: BLE001 - cancelled or still ending: nothing more to wait for
                pass
        raise


def utilisation_plot(r, limit: float, path: str | Path, label: str, allowable: str,
                     cache: Cache | None = None) -> Path:
    """:func:`rigfem.report.pictures.utilisation_plot` through ``cache``."""
    path = Path(path)
    inputs = {"curve": [r.case.rows, r.vm_rows], "limit": limit, "label": label, "allowable": allowable,
              "name": path.name}

    def draw(d: Path) -> tuple[dict, list[str]]:
        from rigfem.report import pictures

        pictures.utilisation_plot(r, limit, d / path.name, label, allowable)
        return {}, [path.name]

    cached("utilisation", inputs, path.parent, draw, resolve(cache))
    return path


def reactions_plot(h, path: str | Path, cache: Cache | None = None) -> None:
    """:func:`rigfem.report.pictures.reactions_plot` through ``cache``."""
    path = Path(path)
    joints = sorted(h.joints)
    mask = h.singular_mask if h.singular_mask is not None else np.zeros(0, bool)
    meta = {k: h.meta.get(k) for k in ("driver_unit", "singular", "lengths_mm", "type", "model")}
    inputs = {"curves": [h.crank_deg, mask, h.torque_Nm, *(h.joints[j].force_N for j in joints)],
              "joints": list(h.joints), "meta": meta, "name": path.name}

    def draw(d: Path) -> tuple[dict, list[str]]:
        from rigfem.report import pictures

        pictures.reactions_plot(h, d / path.name)
        return {}, [path.name]

    cached("reactions", inputs, path.parent, draw, resolve(cache))


def plot_peaks(results: list, limit: float, path: Path, allowable: str, cache: Cache | None = None) -> None:
    """The peaks-over-the-cycle picture of :mod:`rigfem.report.pictures` through the cache."""
    cycle = [r for r in results if r.mode == "cycle"]
    inputs = {"curves": [a for r in cycle for a in (r.case.rows, r.vm_rows)],
              "labels": [(r.case.name, r.case.part) for r in cycle], "limit": limit, "allowable": allowable,
              "name": Path(path).name}

    def draw(d: Path) -> tuple[dict, list[str]]:
        from rigfem.report import pictures

        pictures._plot_peaks(results, limit, d / Path(path).name, allowable)
        return {}, [Path(path).name]

    cached("peaks", inputs, Path(path).parent, draw, resolve(cache))


def write_vtu(path: str | Path, sol, c, allowable: float, cache: Cache | None = None) -> Path:
    """:func:`rigfem.report.vtu.write_vtu` through the cache when ``sol`` is a cached solution
    (its entry's key names its mesh and loads); written directly otherwise."""
    from rigfem.report.vtu import write_vtu as write

    path = Path(path)
    if not sol.key:
        return write(path, sol, c, allowable)
    inputs = {"solution": sol.key, "c": np.asarray(c, dtype=float), "allowable": allowable, "name": path.name}

    def draw(d: Path) -> tuple[dict, list[str]]:
        write(d / path.name, sol, c, allowable)
        return {}, [path.name]

    cached("vtu", inputs, path.parent, draw, resolve(cache))
    return path


def write_frames(folder: Path, names: list[str], sol, coef: np.ndarray, allowable: float,
                 write: Callable[[Path], None], cache: Cache | None = None) -> None:
    """``write(folder)``, which writes the animation frames ``names`` of the load combinations
    ``coef`` (one row a frame) of ``sol``, through the cache when ``sol`` is a cached solution."""
    if not sol.key:
        write(folder)
        return
    inputs = {"solution": sol.key, "c": np.asarray(coef, dtype=float), "allowable": allowable, "names": names}

    def draw(d: Path) -> tuple[dict, list[str]]:
        write(d)
        return {}, names

    cached("frames", inputs, folder, draw, resolve(cache))
