"""Data of the report's offline 3-D view: each part's surface and its utilisation per crank angle,
its supports and the pin loads on its holes per crank angle.

Read from the cycle animation the check wrote (``<part>_cycle.pvd``, its compact VTU frames and
``<part>_cycle_markers.json``), so the view shows exactly the files in the folder.  Compact: float32 surface vertices, uint32
triangles and uint16 utilisation in 0.01 % steps, base64 in the page (``viewer.js`` draws it).
"""

from __future__ import annotations

import base64
import json
import re
from pathlib import Path

import meshio
import numpy as np

from rigfem.files import file_sha256
from rigfem.cache import Cache, resolve

__all__ = ["viewer_data"]

_DATASET = re.compile(r'<DataSet\s+timestep="([^"]+)"\s+file="([^"]+)"')
#: utilisation is stored in 0.01 % steps up to this cap (above it the colour is the same)
CAP_PCT = 600.0


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def _surface(tets: np.ndarray) -> np.ndarray:
    """The boundary triangles of a tetrahedral mesh (faces that belong to one element only)."""
    faces = np.concatenate([tets[:, [0, 1, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 3]], tets[:, [1, 2, 3]]])
    _, first, count = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    return faces[first[count == 1]]


def _part(pvd: Path, limit_mpa: float) -> dict | None:
    series = [(float(t), pvd.parent / f) for t, f in _DATASET.findall(pvd.read_text())]
    if not series or not all(f.is_file() for _, f in series):
        return None
    first = meshio.read(series[0][1])
    tri = _surface(first.cells_dict["tetra"][:, :4])
    used, tri = np.unique(tri, return_inverse=True)
    util = []
    for _, f in series:
        vm = meshio.read(f).point_data["von_mises"][used].astype(float)
        util.append(np.clip(np.nan_to_num(vm / limit_mpa * 100.0, nan=0.0, posinf=CAP_PCT), 0.0, CAP_PCT))
    util = np.array(util)
    return {"name": pvd.stem.removesuffix("_cycle"), "angles": [t for t, _ in series],
            "vertices": int(used.size), "pos": _b64(first.points[used].astype("<f4")),
            # vertex indices in 2 bytes where they fit (most parts): the page carries half the triangles' bytes
            "tri": _b64(tri.reshape(-1, 3).astype("<u2" if used.size <= 2**16 else "<u4")),
            "tri_bytes": 2 if used.size <= 2**16 else 4, "util": _b64(np.round(util * 100).astype("<u2")),
            "peak": [float(u.max()) for u in util], "governing": int(np.argmax(util.max(axis=1))),
            **_markers(_markers_file(pvd), used, len(series))}


def _markers_file(pvd: Path) -> Path:
    """The markers written beside an animation (rigfem.report.check): ``<part>_cycle_markers.json``."""
    return pvd.with_name(f"{pvd.stem}_markers.json")


def _markers(path: Path, used: np.ndarray, frames: int) -> dict:
    """The view's supports and pin loads from the animation's markers file: ``held`` (per surface vertex
    of the view, 0 or the number of its support in ``supports``), ``free_body``, and per frame each
    loaded hole's ``name``, centre ``at`` (mm) and ``force`` (N); none when the file is absent (an
    animation written before the markers were)."""
    if not path.is_file():
        return {"held": None, "supports": [], "free_body": False, "loads": [[] for _ in range(frames)]}
    m = json.loads(path.read_text())
    held = np.zeros(used.size, "<u1")
    for k, s in enumerate(m["supports"], start=1):
        v = np.asarray(s["vertices"], int)
        i = np.searchsorted(used, v).clip(0, used.size - 1)
        held[i[used[i] == v]] = k
    return {"held": _b64(held), "supports": [f"{s['name']} ({s['kind']})" for s in m["supports"]],
            "free_body": bool(m["free_body"]),
            "loads": [[{"name": ld["hole"], "at": ld["at_mm"], "force": ld["force_N"]} for ld in f["loads"]]
                      for f in m["frames"]]}


def _cached_part(pvd: Path, limit_mpa: float, cache: Cache) -> dict | None:
    """:func:`_part` through a verified cache entry keyed by the SHA-256 of the animation's files:
    a warm check wrote the same frames, and reading them back with meshio costs a second."""
    series = [pvd.parent / f for _, f in _DATASET.findall(pvd.read_text())]
    if not series or not all(f.is_file() for f in series):
        return None
    marks = [_markers_file(pvd)] if _markers_file(pvd).is_file() else []
    inputs = {"files": [file_sha256(f) for f in [pvd, *series, *marks]], "limit_mpa": limit_mpa,
              "meshio": meshio.__version__}
    part, _ = cache.cached("viewer", inputs, lambda: _part(pvd, limit_mpa),
                           lambda part, tmp: (tmp / "part.json").write_text(json.dumps(part)),
                           lambda entry: entry.json("part.json"))
    return part


def viewer_data(folder: Path, files: list[str], limit_mpa: float, cache: Cache | None = None) -> list[dict]:
    """One entry per part with a cycle animation among ``files`` (none if the folder has none)."""
    parts = [_cached_part(folder / f, limit_mpa, resolve(cache)) for f in files
             if f.endswith("_cycle.pvd") and (folder / f).is_file()]
    return [p for p in parts if p is not None]
