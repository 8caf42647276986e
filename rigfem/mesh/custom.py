"""A user's own part file (.geo, .step, .brep: ``kind = "custom"``) read by gmsh: a boundary.

The file is user input as much as a scene is: gmsh parses it (in a child first, so a bad file
is one line naming it, not a crash), and it must hold a volume and named surfaces to attach loads
to.  Each refusal is one InputError line naming the file (tests/test_boundaries.py lists this
module among the boundaries).
"""

from __future__ import annotations

import gmsh

from rigfem.errors import InputError, plain
from rigfem.mesh.partmesh import Hole
from rigfem.rig.parts import PartDef

_PARSE = """
import sys, gmsh
gmsh.initialize(interruptible=False)
gmsh.option.setNumber("General.Terminal", 1)
try:
    if sys.argv[1].lower().endswith(".geo"):
        gmsh.open(sys.argv[1])
    else:
        gmsh.option.setString("Geometry.OCCTargetUnit", "MM")
        gmsh.merge(sys.argv[1])
except Exception as exc:
    print("RIGFEM-PARSE-ERROR", exc, flush=True)
    sys.exit(1)
"""


def check_parses(path) -> None:
    """InputError with gmsh's line and message if gmsh cannot read the part file ``path``."""
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-c", _PARSE, str(path)], capture_output=True, text=True, timeout=600)
    if r.returncode == 0:
        return
    said = (r.stdout + r.stderr).splitlines()
    why = next((x.split("RIGFEM-PARSE-ERROR", 1)[1].strip() for x in said if "RIGFEM-PARSE-ERROR" in x), "")
    detail = next((plain(x, 160).strip(" *") for x in said if ("ERR" in x or "rror" in x)
                   and "RIGFEM-PARSE-ERROR" not in x), "")
    raise InputError(f"part file {plain(path, 120)}: gmsh cannot read it: {plain(why or r.returncode, 160)}"
                     + (f" ({detail})" if detail and why not in detail else ""))


def build_custom(part: PartDef) -> dict[str, Hole]:
    assert part.path is not None
    check_parses(part.path)
    if part.path.suffix.lower() == ".geo":
        gmsh.open(str(part.path))
    else:
        gmsh.option.setString("Geometry.OCCTargetUnit", "MM")
        gmsh.merge(str(part.path))
        gmsh.model.occ.synchronize()
    if part.path.suffix.lower() != ".geo":
        by_name: dict[str, list[int]] = {}
        for _, tag in gmsh.model.getEntities(2):  # named faces (CAD labels) become surface groups
            label = gmsh.model.getEntityName(2, tag)
            if label:
                by_name.setdefault(label.split("/")[-1], []).append(tag)
        for label, tags in by_name.items():
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, tags), label)
    vols = gmsh.model.getEntities(3)
    if not vols:
        raise InputError(f"custom part {part.path}: no volume in the file")
    if not gmsh.model.getPhysicalGroups(3):
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [t for _, t in vols]), part.name)
    if not gmsh.model.getPhysicalGroups(2):
        raise InputError(f"custom part {part.path}: no named surface to attach loads to; name faces in the "
                         f"CAD file or wrap it in a .geo file (Merge \"{part.path.name}\"; Physical Surface(\"pin\") = {{..}};)")
    return {}




def check_occ(part: PartDef) -> None:
    """A custom part's volume is measured in the OpenCASCADE kernel: InputError when its file
    built the geometry in gmsh's built-in kernel (call inside a gmsh session, after building)."""
    if not gmsh.model.occ.getEntities(3):
        raise InputError(f"custom part {part.path}: volume needs an OpenCASCADE geometry")
