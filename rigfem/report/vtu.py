"""VTU output through meshio: opens in ParaView, warp-by-vector on ``displacement`` works.

P2 models are written as ``tetra10`` cells (VTK quadratic tetra, same node order
as C3D10), P1 as ``tetra``.  Point data: ``displacement`` (3), ``stress`` (6,
Voigt xx, yy, zz, xy, yz, xz), ``von_mises`` and ``safety_factor`` =
allowable / von Mises, capped at
``SAFETY_CAP`` where the stress is (near) zero so no inf is written.
"""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np

from rigfem.fe.solution import Solution
from rigfem.tensors import von_mises

SAFETY_CAP = 100.0


def write_vtu(path: str | Path, sol: Solution, c, allowable: float) -> Path:
    """Write the combination ``c`` of load cases (None: the only case) of ``sol`` as VTU, its safety
    factor against the ``allowable`` stress (MPa)."""
    fm, allow = sol.model.mesh, float(allowable)
    s = sol.stress(c)
    vm = von_mises(s)
    sf = np.minimum(allow / np.maximum(vm, allow / SAFETY_CAP), SAFETY_CAP)
    data = {"displacement": sol.displacement(c), "stress": s, "von_mises": vm, "safety_factor": sf}
    mesh = meshio.Mesh(fm.nodes, [("tetra10" if fm.order == 2 else "tetra", fm.elements)], point_data=data)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mesh.write(path, file_format="vtu", compression=None)  # float data barely compresses: zlib costs time
    return path


def write_frame(path: str | Path, vertices: np.ndarray, tets: np.ndarray, fields: dict[str, np.ndarray],
                allowable: float) -> Path:
    """Write one animation frame (:func:`rigfem.fe.partcase.finish`'s vertex fields, float32) as a
    compact VTU: linear ``tetra`` cells on the vertices, with the safety factor against ``allowable``."""
    vm = fields["von_mises"].astype(float)
    sf = np.minimum(allowable / np.maximum(vm, allowable / SAFETY_CAP), SAFETY_CAP).astype(np.float32)
    mesh = meshio.Mesh(vertices.astype(np.float32), [("tetra", tets.astype(np.int32))],
                       point_data={**fields, "safety_factor": sf})
    mesh.write(path, file_format="vtu", compression=None)
    return Path(path)
