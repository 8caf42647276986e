"""Render the rail, the coupling plate and the I-profile to PNG with the named interfaces coloured.

Run: ``python benchmarks/render_parts.py`` -> results/parts/*.png (matplotlib 3-D of the boundary
triangles of the tet mesh; grey = boundary outside any named interface group).
Also prints mesh times and element counts of the 700 and 1000 mm rails at the default size.
"""

from __future__ import annotations

import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from rigfem.cache import NO_CACHE
from rigfem.mesh import DEFAULT_SIZE, MeshSettings, PartMesh, boundary_faces, mesh_part
from rigfem.rig import load_part, rail_hole_groups, rail_hole_x

OUT = Path(__file__).resolve().parents[1] / "results" / "parts"


def colour_of(name: str, loaded: set[str]) -> str:
    """One colour per kind of interface; loaded (refined) holes stand out in red."""
    if name in loaded:
        return "#d62728"
    if name.startswith("cbore_floor"):
        return "#ffbf00"
    if name.startswith("cbore"):
        return "#ff7f0e"
    if name.startswith(("hole_", "screw_")):
        return "#1f77b4"
    return {"bore": "#9467bd", "bottom": "#8fbf8f", "base": "#8fbf8f", "top": "#c7c7e8",
            "ends": "#2ca02c", "sides": "#d9d9d9", "rim": "#d9d9d9"}.get(name, "#7f7f7f")


def draw(ax, pm: PartMesh, loaded: set[str], box: tuple[np.ndarray, np.ndarray] | None = None,
         zoom: float = 1.0) -> dict[str, str]:
    """Draw the boundary of ``pm`` (optionally only triangles inside ``box``); return legend colours."""
    faces = {tuple(sorted(t)): "#bdbdbd" for t in boundary_faces(pm.tets)}
    tri_of = {tuple(sorted(t)): t for t in boundary_faces(pm.tets)}
    legend: dict[str, str] = {}
    for name, tris in pm.surfaces.items():
        c = colour_of(name, loaded)
        for t in tris:
            faces[tuple(sorted(t))] = c
        label = ("loaded hole (refined)" if name in loaded else
                 "cbore floor" if name.startswith("cbore_floor") else
                 "cbore wall" if name.startswith("cbore") else
                 "hole / screw wall" if name.startswith(("hole_", "screw_")) else name)
        legend.setdefault(label, c)
    keys = list(faces)
    verts = pm.points[np.array([tri_of[k] for k in keys])]
    cols = np.array([faces[k] for k in keys])
    if box is not None:
        inside = ((verts >= box[0]) & (verts <= box[1])).all(axis=(1, 2))
        verts, cols = verts[inside], cols[inside]
    coll = Poly3DCollection(verts, facecolors=cols, edgecolors="k", linewidths=0.08, shade=True)
    ax.add_collection3d(coll)
    lo, hi = verts.reshape(-1, 3).min(0), verts.reshape(-1, 3).max(0)
    ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(hi - lo, zoom=zoom)
    ax.set_xlabel("x mm"), ax.set_ylabel("y mm"), ax.set_zlabel("z mm")
    return legend


def figure(pm: PartMesh, loaded: set[str], title: str, path: Path, zoom=None, view=(28, -58),
           zoom_view=(55, -70)) -> None:
    """One PNG: the whole part, and if ``zoom`` (a box) is given, a large close-up of that box."""
    legend: dict[str, str] = {}
    if zoom is None:
        fig = plt.figure(figsize=(13, 7))
        ax = fig.add_subplot(1, 1, 1, projection="3d")
        legend |= draw(ax, pm, loaded)
        ax.view_init(*view)
        ax.set_title(title, fontsize=10)
    else:
        fig = plt.figure(figsize=(13, 9))
        ax = fig.add_axes([-0.1, 0.66, 1.0, 0.34], projection="3d")
        legend |= draw(ax, pm, loaded)
        ax.view_init(*view)
        ax.set_title(title, fontsize=10)
        ax = fig.add_axes([-0.05, 0.0, 0.92, 0.7], projection="3d")
        legend |= draw(ax, pm, loaded, zoom, zoom=0.95)
        ax.view_init(*zoom_view)
        ax.set_title(f"cut-away close-up: x in [{zoom[0][0]:g}, {zoom[1][0]:g}] mm, half y <= 0 seen from +y", fontsize=9)
    fig.legend(handles=[Patch(color=c, label=k) for k, c in legend.items()], loc="center right", fontsize=8)
    q = pm.quality
    fig.text(0.01, 0.01, f"{len(pm.points)} nodes, {len(pm.tets)} linear tets, minSICN min {q['min']:.2f} "
             f"median {q['median']:.2f}", fontsize=8)
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {path}")


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for L in (700, 1000):  # timing at the default size, refined at pivot and far-end couplings
        part = load_part("rail_size25", {"length": L})
        n = len(rail_hole_x(part))
        loaded = ("hole_00", "hole_02", f"hole_{n - 3:02d}", f"hole_{n - 1:02d}")
        t = time.perf_counter()
        pm = mesh_part(part, MeshSettings(DEFAULT_SIZE["rail"], loaded), cache=NO_CACHE)
        print(f"rail {L} mm: size {DEFAULT_SIZE['rail']} mm, refined {loaded}: {len(pm.points)} nodes, "
              f"{len(pm.tets)} tets, minSICN min {pm.quality['min']:.3f}, {time.perf_counter() - t:.2f} s")
    part = load_part("rail_size25", {"length": 700})
    loaded = {rail_hole_groups(i)[0] for i in (9, 11)}
    pm = mesh_part(part, MeshSettings(DEFAULT_SIZE["rail"], tuple(loaded)))
    figure(pm, loaded, "rail_size25, 700 mm, far-end coupling holes 09 and 11 refined",
           OUT / "rail_size25_700.png", zoom=(np.array([540, -20, -1]), np.array([701, 1e-6, 30])), view=(32, -62),
           zoom_view=(25, 70))
    part = load_part("PF_4b_006")
    loaded = {"screw_1", "screw_2", "bore"}
    pm = mesh_part(part, MeshSettings(DEFAULT_SIZE["plate"], tuple(loaded)))
    figure(pm, loaded - {"bore"}, "PF_4b_006 coupling plate (bore = 6205 seat, screws refined)",
           OUT / "PF_4b_006.png", view=(35, -70))
    part = load_part("PF_4b_003_v2")
    loaded = {"screw_1", "screw_2", "screw_3", "screw_4"}
    pm = mesh_part(part, MeshSettings(DEFAULT_SIZE["iprofile"], tuple(loaded), concentrate=("fillets",)))
    figure(pm, set(), f"PF_4b_003_v2 I-profile (root fillets r = {part['fillet_radius']:g} mm at half the "
           "screws' size; screw_1..4 refined; base and top faces)",
           OUT / "PF_4b_003_v2.png", view=(25, -35))


if __name__ == "__main__":
    main()
