"""VTU output: opens in ParaView, warp-by-vector on ``displacement`` works.

P2 models are written as ``tetra10`` cells (VTK quadratic tetra, same node order
as C3D10), P1 as ``tetra``.  Point data: ``displacement`` (3, mm), ``stress`` (6,
MPa, Voigt xx, yy, zz, xy, yz, xz), ``von_mises`` (MPa) and ``safety_factor`` =
allowable / von Mises, capped at ``SAFETY_CAP`` where the stress is (near) zero so
no inf is written.

The files are written by VTK's own XML writer, through PyVista (the library ParaView reads them
with; meshio reads them too): appended raw binary data (no base64, which adds a third), zlib-compressed at level 1
(the float32 fields barely compress: a higher level costs time for little), every array float32 —
node coordinates too (mm: 7 significant digits, below 1e-4 mm on a metre-long part) — and
connectivity Int32: same arrays, same names, a few times smaller than uncompressed float64 files
(results/benchmarks/folder_size.json).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rigfem.errors import ComputeError
from rigfem.fe.solution import Solution
from rigfem.tensors import von_mises

SAFETY_CAP = 100.0


#: VTK's cell type of each cell kind written (the node order is VTK's, which is C3D10's for tetra10)
VTK_CELL = {"tetra": 10, "tetra10": 24}


def write_unstructured(path: str | Path, points: np.ndarray, cell_type: str, cells: np.ndarray,
                       point_data: dict[str, np.ndarray]) -> Path:
    """Write one cell kind's unstructured grid with its point data as VTK XML (VTK's writer: appended
    raw binary, zlib level 1, Int32 connectivity); arrays keep the dtype they come in: the caller
    chooses the precision.  Arrays are listed in ``point_data``'s order (ParaView's list)."""
    import pyvista as pv

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    grid = pv.UnstructuredGrid({VTK_CELL[cell_type]: np.asarray(cells, dtype=np.int64)}, np.asarray(points))
    for name, values in point_data.items():
        grid.point_data[name] = np.asarray(values)
    w = pv.XMLUnstructuredGridWriter(path, grid).writer  # PyVista's handle on VTK's own writer
    w.WriteToOutputStringOn()  # the file is written by Python: a full disk is an OSError naming it
    w.SetInputData(grid)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()
    w.SetCompressorTypeToZLib()
    w.SetCompressionLevel(1)
    w.SetIdTypeToInt32()
    if not w.Write():
        raise ComputeError(f"VTK could not encode {path.name}")
    data = w.GetOutputString()  # VTK's wrapper: bytes, or str where the bytes happen to be valid UTF-8
    path.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))
    return path


def _safety(vm: np.ndarray, allowable: float) -> np.ndarray:
    vm = np.asarray(vm, dtype=float)
    return np.minimum(allowable / np.maximum(vm, allowable / SAFETY_CAP), SAFETY_CAP)


def write_vtu(path: str | Path, sol: Solution, c, allowable: float) -> Path:
    """Write the combination ``c`` of load cases (None: the only case) of ``sol`` as VTU, its safety
    factor against the ``allowable`` stress (MPa); every array float32 (computed in float64)."""
    fm, allow = sol.model.mesh, float(allowable)
    s = sol.stress(c)
    vm = von_mises(s)
    data = {"displacement": sol.displacement(c), "stress": s, "von_mises": vm, "safety_factor": _safety(vm, allow)}
    return write_unstructured(path, fm.nodes.astype(np.float32), "tetra10" if fm.order == 2 else "tetra",
                              fm.elements, {k: v.astype(np.float32) for k, v in data.items()})


def write_frame(path: str | Path, vertices: np.ndarray, tets: np.ndarray, fields: dict[str, np.ndarray],
                allowable: float) -> Path:
    """Write one animation frame (:func:`rigfem.fe.partcase.finish`'s vertex fields, float32) as a
    compact VTU: linear ``tetra`` cells on the vertices, with the safety factor against ``allowable``."""
    sf = _safety(fields["von_mises"], float(allowable))
    return write_unstructured(path, vertices.astype(np.float32), "tetra", tets,
                              {**{k: np.asarray(v, np.float32) for k, v in fields.items()},
                               "safety_factor": sf.astype(np.float32)})
