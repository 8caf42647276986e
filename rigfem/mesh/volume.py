"""A part's volume and mass: computed by OpenCASCADE (gmsh) once per part definition, then cached.

``rigfem parts`` lists every part's mass; building each solid in gmsh costs a few tenths of a
second and the gmsh import alone more, so the volume is a verified cache entry
(:mod:`rigfem.mesh.cache`) keyed by the part's content hash and the code that builds it.
"""

from __future__ import annotations

import json

from rigfem.mesh.cache import cache_dir, code_hash, entry_key, read_entry, write_entry
from rigfem.rig.parts import PartDef


def volume_mm3(part: PartDef) -> float:
    """Volume of the part's solid (mm³), from the OCC geometry or its cache entry."""
    inputs = {"part": part.content_hash(), "code": code_hash("mesh/geometry.py", "rig/parts.py")}
    folder = cache_dir() / "volumes" / entry_key(inputs)
    if read_entry(folder, inputs) is not None:
        return float(json.loads((folder / "volume.json").read_text())["mm3"])
    from rigfem.mesh.geometry import occ_volume_mm3  # gmsh: loaded on a cache miss only

    v = occ_volume_mm3(part)
    write_entry(folder, inputs, lambda d: (d / "volume.json").write_text(json.dumps({"mm3": v})))
    return v


def mass_kg(part: PartDef) -> float:
    """Mass of the part, kg (volume in mm³ times density in kg/m³ · 1e-9)."""
    return volume_mm3(part) * part.density * 1e-9
