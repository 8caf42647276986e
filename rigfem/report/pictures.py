"""Pictures of a part's mesh and fields (matplotlib 3-D of the boundary triangles, headless)."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from rigfem.fe.partcase import CaseResult
from rigfem.mesh.partmesh import boundary_faces, whole_file

matplotlib.use("Agg")


def _panel(ax, verts: np.ndarray, vals: np.ndarray, norm, cmap, mark: np.ndarray) -> None:
    colours = cmap(norm(vals))
    ax.add_collection3d(Poly3DCollection(verts, facecolors=colours, edgecolors=colours, linewidths=0.1,
                                         shade=True))
    lo, hi = verts.reshape(-1, 3).min(0), verts.reshape(-1, 3).max(0)
    ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(np.maximum(hi - lo, 0.12 * (hi - lo).max()))  # thin parts stay visible
    ax.scatter(*mark, color="k", marker="x", s=60, depthshade=False)
    ax.set_xlabel("x mm"), ax.set_ylabel("y mm"), ax.set_zlabel("z mm")


def field_picture(points: np.ndarray, tets: np.ndarray, values: np.ndarray, path: str | Path,
                  title: str, label: str = "von Mises (MPa)", zoom_mm: float = 40.0,
                  view: tuple[float, float] = (30, -60)) -> Path:
    """PNG of a nodal field on the part's surface: the whole part and a close-up of its peak."""
    faces = boundary_faces(tets[:, :4])
    verts = points[faces]
    vals = values[faces].mean(axis=1)
    peak = int(np.argmax(values))
    norm = plt.Normalize(0.0, float(values.max()) or 1.0)
    cmap = plt.get_cmap("turbo")
    fig = plt.figure(figsize=(12, 5.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    _panel(ax, verts, vals, norm, cmap, points[peak])
    ax.view_init(*view)
    ax.set_title(title, fontsize=9)
    box = np.abs(verts - points[peak]).max(axis=(1, 2)) <= zoom_mm
    ax = fig.add_subplot(1, 2, 2, projection="3d")
    _panel(ax, verts[box], vals[box], norm, cmap, points[peak])
    ax.view_init(*view)
    ax.set_title(f"close-up ±{zoom_mm:g} mm around the peak {values[peak]:.1f} MPa (×)", fontsize=9)
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=fig.axes, shrink=0.7, label=label)
    path = Path(path)
    with whole_file(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return path


def reactions_plot(h, path: str | Path) -> None:
    """Reaction magnitudes and driver torque against crank angle (singular samples masked)."""
    mask = h.singular_mask if h.singular_mask is not None else np.zeros(h.crank_deg.size, bool)
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for name, j in h.joints.items():
        a1.plot(h.crank_deg, np.ma.masked_where(mask, np.hypot(*j.force_N.T)), label=name)
    a1.set_ylabel("|reaction| (N)")
    a1.legend(ncol=4, fontsize="small")
    a2.plot(h.crank_deg, np.ma.masked_where(mask, h.torque_Nm), color="k")
    a2.set_ylabel("driver torque (N·m)" if h.meta.get("driver_unit", "N·m") == "N·m" else "driver force (N)")
    a2.set_xlabel("crank angle (deg)")
    for a, b in h.meta.get("singular") or []:
        for ax in (a1, a2):
            ax.axvspan(a, b, color="r", alpha=0.2)
    lengths = ", ".join(f"{k} = {v:g}" for k, v in (h.meta.get("lengths_mm") or {}).items())
    a1.set_title(f"{h.meta.get('type', 'linkage')} ({lengths} mm), {h.meta.get('model', '')} dynamics: "
                 f"pin reactions and driver over one crank turn", fontsize="small")
    fig.tight_layout()
    with whole_file(path) as tmp:
        fig.savefig(tmp, dpi=120)
    plt.close(fig)


def _plot_peaks(results: list[CaseResult], limit: float, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for r in results:
        if r.mode == "cycle":
            ax.plot(r.case.rows, r.vm_rows, label=r.case.name)
    ax.axhline(limit, color="r", ls="--", label=f"limit {limit:.0f} MPa")
    ax.set_xlabel("crank angle (deg)"), ax.set_ylabel("peak von Mises (MPa)")
    ax.set_yscale("log")
    ax.legend(fontsize="small", ncol=3)
    ax.set_title("peak von Mises stress per part over the crank cycle (cycle mode)", fontsize="small")
    fig.tight_layout()
    with whole_file(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def utilisation_plot(r: CaseResult, limit: float, path: str | Path) -> Path:
    """Peak von Mises of a part over the crank cycle (cycle mode) with the allowable stress."""
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(r.case.rows, r.vm_rows, color="#1565c0", label="peak von Mises of the part")
    ax.axhline(limit, color="#c62828", ls="--", label=f"allowable σu/2 = {limit:.0f} MPa")
    i = int(np.argmax(r.vm_rows))
    ax.plot(r.case.rows[i], r.vm_rows[i], "o", color="k")
    ax.annotate(f"{r.vm_rows[i]:.1f} MPa at {r.case.rows[i]:.0f}° ({100 * r.vm_rows[i] / limit:.1f} %)",
                (r.case.rows[i], r.vm_rows[i]), textcoords="offset points", xytext=(8, 8), fontsize=9)
    ax.set_ylim(0, max(limit, float(r.vm_rows.max())) * 1.08)
    ax.set_xlim(0, 360)
    ax.set_xlabel("crank angle (°)")
    ax.set_ylabel("peak von Mises (MPa)")
    ax.set_title(f"{r.case.name}: peak von Mises over the crank cycle against the allowable stress")
    ax.legend(loc="upper right", fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path = Path(path)
    with whole_file(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return path


def render_field(r: CaseResult, c: np.ndarray, limit: float, path: str | Path,
                 size: tuple[int, int] = (1600, 1000), zoom_mm: float = 30.0) -> str:
    """von Mises on the deformed part (PyVista, off-screen): the whole part and a close-up of the
    peak with the mesh edges; supports and loaded surfaces outlined, the peak marked.

    Returns ``"pyvista"``, or ``"matplotlib"`` where no 3-D renderer can run (the picture is then
    the simpler matplotlib view).
    """
    title = f"{r.case.name} ({r.mode} mode): von Mises at crank {r.case.rows[r.row]:.1f}°"
    fm = r.solution.model.mesh
    vm = r.solution.von_mises(c)
    try:
        import pyvista as pv
    except ImportError:  # pragma: no cover - pyvista is a dependency; kept for broken GL stacks
        field_picture(fm.nodes, fm.elements, vm, path, title)
        return "matplotlib"
    pv.OFF_SCREEN = True
    u = r.solution.displacement(c)
    span = float(np.ptp(fm.nodes, axis=0).max())
    umax = float(np.linalg.norm(u, axis=1).max())
    scale = _nice(0.04 * span / umax) if umax > 0 else 1.0
    peak = int(np.argmax(vm))
    top = limit if vm[peak] >= 0.5 * limit else float(vm[peak])
    grid = pv.UnstructuredGrid({pv.CellType.TETRA: np.asarray(fm.elements[:, :4], np.int64)},
                               fm.nodes + scale * u)
    grid.point_data["von Mises (MPa)"] = vm
    surf = grid.extract_surface(algorithm="dataset_surface")
    marked = {}
    for kind, groups in r.case.supports:
        for g in groups:
            marked.setdefault(g, "support")
    for ld in r.case.loads:
        if ld.kind == "bearing" and ld.group:
            marked[ld.group] = "loaded"
    colours = {"support": "black", "loaded": "magenta"}
    try:
        with pv.vtk_verbosity("error"):  # VTK tries X first and warns on a headless machine
            p = pv.Plotter(off_screen=True, window_size=list(size), shape=(1, 2), border=False)
    except Exception:  # noqa: BLE001 - no OpenGL context on this machine
        field_picture(fm.nodes, fm.elements, vm, path, title)
        return "matplotlib"
    bar = dict(title="von Mises (MPa)", n_labels=6, fmt="%.0f" if top >= 20 else "%.1f",
               vertical=False, position_x=0.2, position_y=0.04, height=0.06, width=0.6)
    x_peak = fm.nodes[peak] + scale * u[peak]
    normal = _normal_at(surf, x_peak)
    for col, close in ((0, False), (1, True)):
        p.subplot(0, col)
        mesh = surf
        if close:
            lo, hi = x_peak - zoom_mm, x_peak + zoom_mm
            mesh = surf.clip_box([lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]], invert=False)
        p.add_mesh(mesh, scalars="von Mises (MPa)", cmap="turbo", clim=[0.0, top], show_edges=close,
                   edge_color="#444444", line_width=0.5, above_color="#7f0000",
                   scalar_bar_args={**bar, "title": "von Mises (MPa)" + " " * col})  # one bar title per view
        for g, kind in marked.items():
            tri = fm.surfaces.get(g)
            if tri is None or len(tri) == 0:
                continue
            faces = np.hstack([np.full((len(tri), 1), 3), np.asarray(tri)[:, :3]]).ravel()
            patch = pv.PolyData(fm.nodes + scale * u, faces)
            rim = patch.extract_feature_edges(boundary_edges=True, feature_edges=False,
                                              manifold_edges=False, non_manifold_edges=False)
            if close:  # only the outlines inside the close-up's box
                rim = rim.clip_box([lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]], invert=False)
            if rim.n_points:
                p.add_mesh(rim, color=colours[kind], line_width=3)
        p.add_point_labels(pv.PolyData(x_peak[None, :]), [f"peak {vm[peak]:.1f} MPa"], point_size=14,
                           point_color="white", font_size=20 if close else 16, shape_opacity=0.7,
                           always_visible=True)
        d = normal + 0.35 * np.array([0.0, 0.0, 1.0]) + 0.25 * np.array([1.0, -1.0, 0.0])
        d /= np.linalg.norm(d)
        p.view_vector(d, viewup=(0.0, 0.0, 1.0) if abs(d[2]) < 0.9 else (0.0, 1.0, 0.0))
        p.reset_camera(bounds=mesh.bounds)
        p.camera.zoom(1.15 if close else 0.9)
        if close:
            p.add_text(f"close-up ±{zoom_mm:g} mm around the peak, mesh edges shown", font_size=11,
                       position="upper_left")
        else:
            p.add_text(f"{title}\ndeformation ×{scale:g}; colour bar top = "
                       f"{'allowable' if top == limit else 'peak'} {top:.0f} MPa (allowable {limit:.0f} MPa)\n"
                       f"black: supports, magenta: loaded holes", font_size=11, position="upper_left")
    p.screenshot(str(path))
    p.close()
    return "pyvista"


def _nice(x: float) -> float:
    """x rounded down to 1, 2 or 5 × a power of ten."""
    e = 10.0 ** np.floor(np.log10(x))
    return float(max(m for m in (1.0, 2.0, 5.0) if m * e <= x) * e) if x > 0 else 1.0


def _normal_at(surf, x: np.ndarray) -> np.ndarray:
    """Outward unit normal of the surface point nearest to ``x``."""
    n = surf.compute_normals(auto_orient_normals=True, cell_normals=False)
    i = int(np.argmin(np.linalg.norm(n.points - x, axis=1)))
    v = np.asarray(n.point_data["Normals"][i], float)
    return v / (np.linalg.norm(v) or 1.0)
