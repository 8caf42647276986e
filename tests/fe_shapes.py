"""Test PartMesh builders: their one home is :mod:`rigfem.verification.shapes` (the band-coverage study meshes them too)."""

from rigfem.verification.shapes import (  # noqa: F401
    FACES,
    bar_with_holes,
    box,
    faces_at,
    gmsh_part,
    plate_with_hole,
    quarter_ring,
)
