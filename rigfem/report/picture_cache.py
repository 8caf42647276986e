"""Pictures and field files through the cache: each is a pure function of what it is drawn from.

Rendering a part's pictures costs seconds (pyvista and matplotlib); a warm check draws the same
pictures again from the same cached solution.  Each call below hashes everything its picture is
drawn from (the field arrays, the mesh, the titles and labels, the report code that draws them
and the plotting libraries' versions) into the key of a verified cache entry
(:mod:`rigfem.mesh.cache`: a SHA-256 per file, a corrupt entry is discarded and drawn again) under
``$RIGFEM_CACHE/pictures``, and a hit copies the stored PNG files: byte for byte the pictures a
cold run drew, without pyvista.  A fallback picture (matplotlib,
where no OpenGL runs) is not stored: a machine that gains OpenGL draws the real one.  The VTU
field files of a cached solution (:func:`write_vtu`) are stored the same way, keyed by the
solution's entry and the load combination.

The drawing code (matplotlib) is imported only where a picture is drawn, so a warm check, which
draws none, does not import it.
"""

from __future__ import annotations

import functools
import json
import shutil
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rigfem.mesh.cache import array_digest, cache_dir, code_hash, entry_key, read_entry, write_entry

#: the source files that draw the pictures: an edit invalidates every stored picture
PICTURE_CODE = ("report/pictures.py", "report/views.py", "report/vtu.py", "report/picture_cache.py",
                "mesh/partmesh.py")
_RESULT = "result.json"


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


def cached(kind: str, inputs: dict, folder: Path, draw: Callable[[Path], tuple[dict, list[str]]]) -> dict:
    """``draw(folder)`` -> (result, file names it wrote in ``folder``), or the stored files copied
    into ``folder`` and the stored result when an entry of ``inputs`` is in the cache."""
    inputs = {"kind": kind, **inputs, "code": code_hash(*PICTURE_CODE), "libraries": _versions()}
    entry = cache_dir() / "pictures" / entry_key(inputs)
    if read_entry(entry, inputs) is not None:
        try:
            stored = json.loads((entry / _RESULT).read_text())
            for name in stored["files"]:
                shutil.copyfile(entry / name, folder / name)
            return stored["result"]
        except (OSError, ValueError, KeyError, TypeError):
            pass  # verified, yet unreadable here: draw it
    result, files = draw(folder)
    if result.get("renderer", "pyvista") == "pyvista":

        def write(tmp: Path) -> None:
            for name in files:
                shutil.copyfile(folder / name, tmp / name)
            (tmp / _RESULT).write_text(json.dumps({"files": files, "result": result}))

        write_entry(entry, inputs, write)
    return result


def part_pictures(r, c: np.ndarray, entry: dict, limit: float, label: str, allowable: str,
                  folder: str | Path, zoom_mm: float = 30.0) -> dict:
    """:func:`rigfem.report.pictures.part_pictures` through the cache (same arguments, same result)."""
    sol, fm = r.solution, r.solution.model.mesh
    groups = sorted(fm.surfaces)
    inputs = {"fields": array_digest(sol.von_mises(c), sol.displacement(c), sol.F @ c),
              "mesh": array_digest(fm.nodes, fm.elements, *(fm.surfaces[g] for g in groups)), "groups": groups,
              "n_vertices": fm.n_vertices, "case": r.case.name, "mode": r.mode,
              "crank_deg": float(r.case.rows[r.row]),
              "loads": [(ld.kind, ld.group) for ld in r.case.loads], "supports": r.case.supports,
              "entry": {k: entry[k] for k in ("utilisation_pct", "error_pct", "verdict")},
              "limit": limit, "label": label, "allowable": allowable, "zoom_mm": zoom_mm}

    def draw(d: Path) -> tuple[dict, list[str]]:
        from rigfem.report import pictures

        out = pictures.part_pictures(r, c, entry, limit, label, allowable, d, zoom_mm)
        return out, list(out["files"].values())

    return cached("part", inputs, Path(folder), draw)


def utilisation_plot(r, limit: float, path: str | Path, label: str, allowable: str) -> Path:
    """:func:`rigfem.report.pictures.utilisation_plot` through the cache."""
    path = Path(path)
    inputs = {"curve": array_digest(r.case.rows, r.vm_rows), "limit": limit, "label": label, "allowable": allowable,
              "name": path.name}

    def draw(d: Path) -> tuple[dict, list[str]]:
        from rigfem.report import pictures

        pictures.utilisation_plot(r, limit, d / path.name, label, allowable)
        return {}, [path.name]

    cached("utilisation", inputs, path.parent, draw)
    return path


def reactions_plot(h, path: str | Path) -> None:
    """:func:`rigfem.report.pictures.reactions_plot` through the cache."""
    path = Path(path)
    joints = sorted(h.joints)
    mask = h.singular_mask if h.singular_mask is not None else np.zeros(0, bool)
    meta = {k: h.meta.get(k) for k in ("driver_unit", "singular", "lengths_mm", "type", "model")}
    inputs = {"curves": array_digest(h.crank_deg, mask, h.torque_Nm, *(h.joints[j].force_N for j in joints)),
              "joints": list(h.joints), "meta": meta, "name": path.name}

    def draw(d: Path) -> tuple[dict, list[str]]:
        from rigfem.report import pictures

        pictures.reactions_plot(h, d / path.name)
        return {}, [path.name]

    cached("reactions", inputs, path.parent, draw)


def plot_peaks(results: list, limit: float, path: Path, allowable: str) -> None:
    """The peaks-over-the-cycle picture of :mod:`rigfem.report.pictures` through the cache."""
    cycle = [r for r in results if r.mode == "cycle"]
    inputs = {"curves": array_digest(*(a for r in cycle for a in (r.case.rows, r.vm_rows))),
              "labels": [(r.case.name, r.case.part) for r in cycle], "limit": limit, "allowable": allowable,
              "name": Path(path).name}

    def draw(d: Path) -> tuple[dict, list[str]]:
        from rigfem.report import pictures

        pictures._plot_peaks(results, limit, d / Path(path).name, allowable)
        return {}, [Path(path).name]

    cached("peaks", inputs, Path(path).parent, draw)


def write_vtu(path: str | Path, sol, c=None, allowable: float | None = None, compact: bool = False) -> Path:
    """:func:`rigfem.report.vtu.write_vtu` through the cache when ``sol`` is a cached solution
    (its entry's key names its mesh, loads and code); written directly otherwise."""
    from rigfem.report.vtu import write_vtu as write

    path = Path(path)
    if not sol.key:
        return write(path, sol, c, allowable, compact)
    inputs = {"solution": sol.key, "c": array_digest(np.asarray(c, dtype=float)), "allowable": allowable,
              "compact": compact, "name": path.name}

    def draw(d: Path) -> tuple[dict, list[str]]:
        write(d / path.name, sol, c, allowable, compact)
        return {}, [path.name]

    cached("vtu", inputs, path.parent, draw)
    return path
