"""VTU output: opens in ParaView, warp-by-vector on ``displacement`` works.

P2 models are written as ``tetra10`` cells (VTK quadratic tetra, same node order
as C3D10), P1 as ``tetra``.  Point data: ``displacement`` (3, mm), ``stress`` (6,
MPa, Voigt xx, yy, zz, xy, yz, xz), ``von_mises`` (MPa) and ``safety_factor`` =
allowable / von Mises, capped at ``SAFETY_CAP`` where the stress is (near) zero so
no inf is written.

The files are VTK XML, binary appended data in raw encoding (no base64: it adds a third)
compressed with zlib, the layout VTK's own writer produces (``vtkXMLUnstructuredGridWriter``
in appended mode with ``vtkZLibDataCompressor``): ParaView, VTK and meshio read them.  Every
array is float32 — node coordinates too (mm: 7 significant digits, below 1e-4 mm on a metre-long
part) — and connectivity int32: same arrays, same names, the critical-angle files 3.6 and the
frames 2.7 times smaller than meshio's uncompressed base64 ones (float64 critical files; results/
benchmarks/folder_size.json).  What is left is mostly the float32 fields themselves: zlib takes
little off them.
"""

from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np

from rigfem.fe.solution import Solution
from rigfem.tensors import von_mises

SAFETY_CAP = 100.0
#: VTK cell type of each cell kind written here
_VTK_TYPE = {"tetra": 10, "tetra10": 24}
_VTU_TYPE = {np.dtype("<f4"): "Float32", np.dtype("<f8"): "Float64", np.dtype("<i4"): "Int32",
             np.dtype("<i8"): "Int64", np.dtype("u1"): "UInt8"}
#: uncompressed bytes per zlib block (VTK's default block size)
BLOCK = 32768
#: zlib level: 1 is within 0.3 % of 6 and 9 on these arrays (float data barely compresses) at half and a third of their time
LEVEL = 1


def _appended(a: np.ndarray) -> bytes:
    """One array as VTK's compressed appended block: UInt64 header (blocks, block size, last
    block's size, each compressed size), then the zlib blocks."""
    raw = np.ascontiguousarray(a).tobytes()
    blocks = [zlib.compress(raw[i:i + BLOCK], LEVEL) for i in range(0, len(raw), BLOCK)] or [zlib.compress(b"")]
    last = len(raw) - (len(blocks) - 1) * BLOCK if raw else 0
    header = np.array([len(blocks), BLOCK, last, *map(len, blocks)], dtype="<u8")
    return header.tobytes() + b"".join(blocks)


def write_unstructured(path: str | Path, points: np.ndarray, cell_type: str, cells: np.ndarray,
                       point_data: dict[str, np.ndarray]) -> Path:
    """Write one cell kind's unstructured grid with its point data as a zlib-compressed VTU
    (appended raw data, UInt64 headers).  Arrays are written with the dtype they come in (little
    endian); the caller chooses the precision."""
    path = Path(path)
    cells = np.asarray(cells)
    n, m = len(points), len(cells)
    arrays = [*((name, np.asarray(v)) for name, v in point_data.items()), (None, np.asarray(points)),
              ("connectivity", cells.astype("<i4").ravel()),
              ("offsets", np.arange(1, m + 1, dtype="<i4") * cells.shape[1]),
              ("types", np.full(m, _VTK_TYPE[cell_type], dtype="u1"))]
    xml, blobs, offset = {}, [], 0
    for name, a in arrays:
        a = a.astype(a.dtype.newbyteorder("<"), copy=False)
        comps = f' NumberOfComponents="{a.shape[1]}"' if a.ndim == 2 else ""
        label = f' Name="{name}"' if name else ""
        xml[name] = (f'<DataArray type="{_VTU_TYPE[a.dtype]}"{label}{comps} format="appended" '
                     f'offset="{offset}"/>')
        blob = _appended(a)
        blobs.append(blob)
        offset += len(blob)
    pd = "\n".join(f"        {xml[k]}" for k in point_data)
    head = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64" compressor="vtkZLibDataCompressor">\n  <UnstructuredGrid>\n'
            f'    <Piece NumberOfPoints="{n}" NumberOfCells="{m}">\n      <PointData>\n{pd}\n      </PointData>\n'
            f'      <Points>\n        {xml[None]}\n      </Points>\n      <Cells>\n'
            + "".join(f"        {xml[k]}\n" for k in ("connectivity", "offsets", "types"))
            + '      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding="raw">\n   _')
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:  # meshio's reader needs the newline after the data
        f.write(head.encode("ascii"))
        for blob in blobs:
            f.write(blob)
        f.write(b"\n  </AppendedData>\n</VTKFile>\n")
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
