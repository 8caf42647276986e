"""A part's volume and mass: computed by OpenCASCADE (gmsh) once per part definition, then cached.

``rigfem parts`` lists every part's mass; building each solid in gmsh costs a few tenths of a
second and the gmsh import alone more, so the volume is a verified cache entry
(:mod:`rigfem.cache`) keyed by the part's content hash.
"""

from __future__ import annotations

import json

from rigfem.cache import Cache, resolve
from rigfem.rig.parts import PartDef


def _occ_volume(part: PartDef) -> float:
    from rigfem.mesh.geometry import occ_volume_mm3  # gmsh: loaded on a cache miss only

    return occ_volume_mm3(part)


def volume_mm3(part: PartDef, cache: Cache | None = None) -> float:
    """Volume of the part's solid (mm³), from the OCC geometry or its cache entry."""
    v, _ = resolve(cache).cached(
        "volumes", {"part": part.content_hash()}, lambda: _occ_volume(part),
        lambda v, tmp: (tmp / "volume.json").write_text(json.dumps({"mm3": v})),
        lambda entry: float(entry.json("volume.json")["mm3"]),
        lambda v: "" if v > 0 else "not a volume")
    return v


def mass_kg(part: PartDef, cache: Cache | None = None) -> float:
    """Mass of the part, kg (volume in mm³ times density in kg/m³ · 1e-9)."""
    return volume_mm3(part, cache) * part.density * 1e-9
