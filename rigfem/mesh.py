"""The mesh of one part: the one data type shared by meshing, the FE solver and the reports.

Units: mm.  A :class:`PartMesh` is what gmsh produced for a part, reduced to plain
arrays (like meshio's ``Mesh``): linear tetrahedra, the named interface surfaces as
triangles, and the geometry of every cylindrical interface (holes, bearing seat) so
loads and supports can attach by name.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Hole:
    """A cylindrical interface surface of a part (screw hole, pivot hole, bearing seat)."""

    center: np.ndarray  #: (3,) mm, point on the axis at mid-depth of the cylinder
    axis: np.ndarray  #: (3,) unit vector along the cylinder axis
    radius: float  #: mm
    depth: float  #: mm, axial length of the cylindrical surface


@dataclass
class PartMesh:
    """Linear tetrahedral mesh of one part with its named interface surfaces."""

    name: str
    points: np.ndarray  #: (N, 3) float, mm
    tets: np.ndarray  #: (M, 4) int, 0-based, positively oriented
    surfaces: dict[str, np.ndarray] = field(default_factory=dict)  #: group name -> (K, 3) triangles
    holes: dict[str, Hole] = field(default_factory=dict)  #: group name -> cylinder geometry
    quality: dict[str, float] = field(default_factory=dict)  #: e.g. {"min": .., "p01": .., "median": ..}
    meta: dict = field(default_factory=dict)  #: part parameters, mesh settings, content hash
