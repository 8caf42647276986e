"""VTU output through meshio: opens in ParaView, warp-by-vector on ``displacement`` works.

P2 models are written as ``tetra10`` cells (VTK quadratic tetra, same node order
as C3D10), P1 as ``tetra``.  Point data: ``displacement`` (3), ``stress`` (6,
Voigt xx, yy, zz, xy, yz, xz), ``von_mises`` and ``safety_factor`` =
allowable / von Mises (allowable defaults to the material's σu/2), capped at
``SAFETY_CAP`` where the stress is (near) zero so no inf is written.
"""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np

from rigfem.errors import InputError
from rigfem.fe.solution import Solution
from rigfem.fe.tensors import von_mises
from rigfem.verdict.criterion import allowable_stress

SAFETY_CAP = 100.0


def write_vtu(path: str | Path, sol: Solution, c=None, allowable: float | None = None,
              compact: bool = False) -> Path:
    """Write the combination ``c`` of load cases (default: the only case) of ``sol`` as VTU.

    ``compact`` writes only the corner nodes with linear ``tetra`` cells in single precision
    (about a tenth of the size): enough for an animation frame, not for reading off peaks.
    """
    fm = sol.model.mesh
    allow = allowable_stress(sol.model.material.sigma_u) if allowable is None else float(allowable)
    if not (np.isfinite(allow) and allow > 0):
        raise InputError(f"allowable = {allowable!r} must be a finite stress > 0")
    s = sol.stress(c)
    vm = von_mises(s)
    sf = np.minimum(allow / np.maximum(vm, allow / SAFETY_CAP), SAFETY_CAP)
    data = {"displacement": sol.displacement(c), "stress": s, "von_mises": vm, "safety_factor": sf}
    if compact:
        n = fm.n_vertices  # vertices come first in the node numbering
        mesh = meshio.Mesh(fm.nodes[:n].astype(np.float32), [("tetra", fm.elements[:, :4].astype(np.int32))],
                           point_data={k: v[:n].astype(np.float32) for k, v in data.items()})
    else:
        cell = "tetra10" if fm.order == 2 else "tetra"
        mesh = meshio.Mesh(fm.nodes, [(cell, fm.elements)], point_data=data)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mesh.write(path, file_format="vtu", compression=None)  # float data barely compresses: zlib costs time
    return path
