"""Part geometry in gmsh's OpenCASCADE kernel: one builder per part kind, every interface a named physical group."""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from typing import Iterator

import gmsh
import numpy as np

from rigfem.mesh.custom import build_custom, check_occ
from rigfem.mesh.partmesh import Hole
from rigfem.rig.parts import PartDef, rail_hole_groups, rail_hole_x


def _restore_python_signal_handlers() -> None:
    """gmsh's initialisation installs its own C signal handlers (SIGTERM then kills the process
    outright); put back Python's, so a terminated run still cleans up (``rigfem.cli``)."""
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGTERM, signal.SIGINT):
            handler = signal.getsignal(sig)
            if handler is not None:
                signal.signal(sig, handler)


@contextmanager
def gmsh_session(model: str = "rigfem") -> Iterator[None]:
    """Quiet gmsh session with a fresh model; finalizes gmsh if this call initialized it."""
    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
        _restore_python_signal_handlers()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.Verbosity", 1)
        gmsh.model.add(model)
        yield
    finally:
        if owner:
            gmsh.finalize()
        else:
            gmsh.model.remove()


def _bbox(tag: int, dim: int = 2) -> np.ndarray:
    return np.array(gmsh.model.getBoundingBox(dim, tag)).reshape(2, 3)


def _close(a: float, b: float, tol: float = 1e-3) -> bool:
    return abs(a - b) <= tol * max(1.0, abs(b))


def _add_groups(groups: dict[str, list[int]], volume: str, vol_tags: list[int]) -> None:
    for name, tags in groups.items():
        if not tags:
            raise RuntimeError(f"geometry of {volume}: surface group {name} came out empty")
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, sorted(tags)), name)
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, vol_tags), volume)


def _vertical_hole(x: float, y: float, z0: float, z1: float, r: float) -> Hole:
    return Hole(np.array([x, y, (z0 + z1) / 2]), np.array([0.0, 0.0, 1.0]), r, z1 - z0)


def _cylinder_at(bb: np.ndarray, x: float, y: float, r: float, tol: float = 1e-3) -> bool:
    """Does the bounding box ``bb`` belong to a vertical cylinder of radius r on axis (x, y)?"""
    c = bb.mean(axis=0)
    return (_close(c[0], x, tol) and _close(c[1], y, tol)
            and _close((bb[1, 0] - bb[0, 0]) / 2, r, tol) and _close((bb[1, 1] - bb[0, 1]) / 2, r, tol))


def _build_rail(part: PartDef) -> dict[str, Hole]:
    occ = gmsh.model.occ
    L, W, H = part["length"], part["width"], part["height"]
    rh, rc, dc = part["hole_diameter"] / 2, part["cbore_diameter"] / 2, part["cbore_depth"]
    xs = rail_hole_x(part)
    body = occ.addBox(0, -W / 2, 0, L, W, H)
    tools = []
    for x in xs:
        tools.append((3, occ.addCylinder(x, 0, -1, 0, 0, H + 2, rh)))
        tools.append((3, occ.addCylinder(x, 0, H - dc, 0, 0, dc + 1, rc)))
    rg = part["groove_radius"]
    if rg > 0:
        for y in (-W / 2, W / 2):
            for z in (part["groove_z_lower"], part["groove_z_upper"]):
                tools.append((3, occ.addCylinder(-1, y, z, L + 2, 0, 0, rg)))
    ww = part["waist_width"]
    steps = (part["waist_z_lower"], part["waist_z_upper"]) if ww > 0 else ()
    if steps:
        za, zb = steps
        for y0 in (-W / 2 - 1, ww / 2):
            tools.append((3, occ.addBox(-1, y0, za, L + 2, (W - ww) / 2 + 1, zb - za)))
    out, _ = occ.cut([(3, body)], tools)
    occ.synchronize()
    names = {"ends": [], "bottom": [], "top": [], "sides": []}
    if rg > 0:
        names["grooves"] = []
    holes: dict[str, Hole] = {}
    for i, x in enumerate(xs):
        bore, cbore, floor = rail_hole_groups(i)
        names[bore], names[cbore], names[floor] = [], [], []
        holes[bore] = _vertical_hole(x, 0.0, 0.0, H - dc, rh)
        holes[cbore] = _vertical_hole(x, 0.0, H - dc, H, rc)
    for _, s in gmsh.model.getEntities(2):
        bb = _bbox(s)
        lo, hi = bb
        if hi[0] - lo[0] < 1e-6:
            names["ends"].append(s)
        elif hi[2] - lo[2] < 1e-6 and _close(lo[2], 0.0):
            names["bottom"].append(s)
        elif hi[2] - lo[2] < 1e-6 and _close(lo[2], H):
            names["top"].append(s)
        elif hi[1] - lo[1] < 1e-6 or (hi[2] - lo[2] < 1e-6 and any(_close(lo[2], z) for z in steps)):
            names["sides"].append(s)
        elif gmsh.model.getType(2, s) == "Cylinder" and hi[0] - lo[0] > L - 1e-3:
            names["grooves"].append(s)
        else:
            i = int(np.argmin(np.abs(xs - bb.mean(axis=0)[0])))
            bore, cbore, floor = rail_hole_groups(i)
            if _cylinder_at(bb, xs[i], 0.0, rh):
                names[bore].append(s)
            elif _cylinder_at(bb, xs[i], 0.0, rc) and gmsh.model.getType(2, s) != "Plane":
                names[cbore].append(s)
            elif _cylinder_at(bb, xs[i], 0.0, rc) and _close(lo[2], H - dc):
                names[floor].append(s)
            else:
                raise RuntimeError(f"rail geometry: surface {s} with bounding box {bb.tolist()} unclassified")
    _add_groups(names, "rail", [t for _, t in out])
    return holes


def _build_plate(part: PartDef) -> dict[str, Hole]:
    occ = gmsh.model.occ
    R, t, rb = part["diameter"] / 2, part["thickness"], part["bore_diameter"] / 2
    rh, w = part["hub_diameter"] / 2, part["seat_width"]
    s, rs = part["screw_spacing"] / 2, part["screw_diameter"] / 2
    zt = max(t, w)
    body = [(3, occ.addCylinder(0, 0, 0, 0, 0, t, R))]
    if w > t:
        hub = occ.addCylinder(0, 0, t, 0, 0, w - t, rh)
        body, _ = occ.fuse(body, [(3, hub)])
    tools = [(3, occ.addCylinder(0, 0, -1, 0, 0, zt + 2, rb))]
    tools += [(3, occ.addCylinder(x, 0, -1, 0, 0, t + 2, rs)) for x in (-s, s)]
    out, _ = occ.cut(body, tools)
    occ.synchronize()
    names = {"bore": [], "screw_1": [], "screw_2": [], "bottom": [], "top": [], "rim": []}
    for _, tag in gmsh.model.getEntities(2):
        bb = _bbox(tag)
        if bb[1, 2] - bb[0, 2] < 1e-6:
            names["bottom" if _close(bb[0, 2], 0.0) else "top"].append(tag)
        elif _cylinder_at(bb, 0.0, 0.0, rb):
            names["bore"].append(tag)
        elif _cylinder_at(bb, -s, 0.0, rs):
            names["screw_1"].append(tag)
        elif _cylinder_at(bb, s, 0.0, rs):
            names["screw_2"].append(tag)
        else:
            names["rim"].append(tag)  # outer disc and hub cylinders
    _add_groups(names, "plate", [t_ for _, t_ in out])
    return {"bore": _vertical_hole(0.0, 0.0, 0.0, zt, rb),
            "screw_1": _vertical_hole(-s, 0.0, 0.0, t, rs),
            "screw_2": _vertical_hole(s, 0.0, 0.0, t, rs)}


def _fillet_web_roots(body: list[tuple[int, int]], Lx: float, h: float, tf: float, tw: float,
                      rf: float) -> list[tuple[int, int]]:
    """Round the four web-flange corners (edges along x at y = +-tw/2, z = tf and h - tf)."""
    occ = gmsh.model.occ
    occ.synchronize()
    roots = []
    for _, e in gmsh.model.getEntities(1):
        lo, hi = _bbox(e, 1)
        if (_close(hi[0] - lo[0], Lx) and _close(abs(lo[1]), tw / 2) and _close(lo[1], hi[1])
                and _close(lo[2], hi[2]) and (_close(lo[2], tf) or _close(lo[2], h - tf))):
            roots.append(e)
    if len(roots) != 4:
        raise RuntimeError(f"I-profile geometry: found {len(roots)} web-flange edges, expected 4")
    return occ.fillet([t for _, t in body], roots, [rf], removeVolume=True)


def _build_iprofile(part: PartDef) -> dict[str, Hole]:
    occ = gmsh.model.occ
    Lx, b, h = part["length"], part["flange_width"], part["height"]
    tf, tw = part["flange_thickness"], part["web_thickness"]
    s, r = part["hole_spacing"] / 2, part["hole_diameter"] / 2
    pieces = [(3, occ.addBox(0, -b / 2, 0, Lx, b, tf)), (3, occ.addBox(0, -b / 2, h - tf, Lx, b, tf)),
              (3, occ.addBox(0, -tw / 2, tf, Lx, tw, h - 2 * tf))]
    body, _ = occ.fuse(pieces[:1], pieces[1:])
    if part["fillet_radius"] > 0:
        body = _fillet_web_roots(body, Lx, h, tf, tw, part["fillet_radius"])
    spots = {"screw_1": (-s, 0.0), "screw_2": (s, 0.0), "screw_3": (-s, h - tf), "screw_4": (s, h - tf)}
    tools = [(3, occ.addCylinder(Lx / 2, y, z0 - 1, 0, 0, tf + 2, r)) for y, z0 in spots.values()]
    out, _ = occ.cut(body, tools)
    occ.synchronize()
    names = {k: [] for k in spots} | {"base": [], "top": []}
    if part["fillet_radius"] > 0:
        names["fillets"] = []
    for _, tag in gmsh.model.getEntities(2):
        bb = _bbox(tag)
        if bb[1, 2] - bb[0, 2] < 1e-6 and _close(bb[0, 2], 0.0):
            names["base"].append(tag)
        elif bb[1, 2] - bb[0, 2] < 1e-6 and _close(bb[0, 2], h):
            names["top"].append(tag)
        elif gmsh.model.getType(2, tag) == "Cylinder" and _close(bb[1, 0] - bb[0, 0], Lx):
            names["fillets"].append(tag)  # the web-flange root fillets run the full length
        else:
            for k, (y, z0) in spots.items():
                if _cylinder_at(bb, Lx / 2, y, r) and _close(bb[0, 2], z0):
                    names[k].append(tag)
    _add_groups(names, "iprofile", [t_ for _, t_ in out])
    return {k: _vertical_hole(Lx / 2, y, z0, z0 + tf, r) for k, (y, z0) in spots.items()}


#: read a part file with gmsh in a child process: a parse error there leaves this process's gmsh
#: parser intact (after a syntax error gmsh misreads the next file once it is re-initialised)
def build(part: PartDef) -> dict[str, Hole]:
    """Create the part's geometry and physical groups in the current gmsh model.

    Returns the analytic cylinder of every hole group (empty for custom parts: the mesh
    step fits cylinders to their surfaces instead).  Call inside :func:`gmsh_session`.
    """
    builders = {"rail": _build_rail, "plate": _build_plate, "iprofile": _build_iprofile,
                "custom": build_custom}
    return builders[part.kind](part)


def occ_volume_mm3(part: PartDef) -> float:
    """Volume of the part's solid from the OCC geometry, mm^3 (cached: :func:`rigfem.mesh.volume.volume_mm3`)."""
    with gmsh_session("volume"):
        build(part)
        vols = gmsh.model.getEntities(3)
        if part.kind == "custom":
            check_occ(part)
        return float(sum(gmsh.model.occ.getMass(d, t) for d, t in vols))
