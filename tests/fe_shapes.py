"""Test PartMesh builders: their one home is :mod:`rigfem.studies.shapes` (the band-coverage study meshes them too)."""

from rigfem.studies.shapes import (  # noqa: F401
    FACES,
    bar_with_holes,
    box,
    faces_at,
    gmsh_part,
    plate_with_hole,
    quarter_ring,
)
