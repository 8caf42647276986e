"""3-D views of a part's nodal field for the report's pictures (PyVista, off-screen).

The camera frames the part so its stressed region shows: the part's long axis lies
horizontal on the screen, a flat part is seen nearly face-on, and the projection is
parallel and fitted to the part's own extent (a long rail fills the width instead of being a
thin diagonal).  Marked points carry their values, pin loads are arrows with their magnitude
in N, supports are dark blocks with their name.  Each view is returned as an RGB image, so
the caller composes the page (title, colour bar) with matplotlib.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: colour of the support symbols and outlines, and of the pin-load arrows
SUPPORT_COLOUR, LOAD_COLOUR = "#202020", "#d81b60"


@dataclass
class FieldView:
    """What one 3-D view shows: a field on the (deformed) part and its annotations."""

    points: np.ndarray  #: (N, 3) node positions drawn, mm (deformed)
    tets: np.ndarray  #: (M, 4) corner connectivity
    values: np.ndarray  #: (N,) the field
    clim: tuple[float, float]
    cmap: str
    above: str | None  #: colour above clim[1] (None: the colour map's top)
    marks: list[tuple[np.ndarray, str]] = field(default_factory=list)  #: (xyz, text) markers
    arrows: list[tuple[np.ndarray, np.ndarray, str]] = field(default_factory=list)  #: (tip, force N, text)
    supports: list[tuple[np.ndarray, str]] = field(default_factory=list)  #: (triangles (K, 3), name)
    ghost: np.ndarray | None = None  #: undeformed node positions, drawn as a faint outline


def framing(points: np.ndarray, focus: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """View direction (towards the camera), view-up and whether the part is elongated.

    The part's principal axes e1 ≥ e2 ≥ e3 (extent): a flat part (e3 < e2/4) is seen along e3,
    tilted a little; otherwise from the side the ``focus``'s outward ``normal`` faces, tilted
    up; either way e1 stays horizontal on the screen.
    """
    x = points - points.mean(0)
    _, _, vt = np.linalg.svd(x[:: max(1, len(x) // 4000)], full_matrices=False)
    ext = np.ptp(x @ vt.T, axis=0)
    e1, e2, e3 = vt
    if ext[2] < 0.25 * ext[1]:
        d = e3 * (1.0 if normal @ e3 >= 0 else -1.0) + 0.35 * e2
    else:
        side = normal - (normal @ e1) * e1
        side = side / np.linalg.norm(side) if np.linalg.norm(side) > 0.1 else e3
        w = np.cross(e1, side)
        w *= 1.0 if w[2] >= 0 else -1.0  # look from above
        d = side + 0.6 * w
    d /= np.linalg.norm(d)
    up = np.cross(d, e1)
    up /= np.linalg.norm(up)
    up *= 1.0 if up[2] >= 0 else -1.0
    return d, up, bool(ext[0] > 3.0 * ext[1])


def _fit(p, pts: np.ndarray, d: np.ndarray, up: np.ndarray, size: tuple[int, int], pad: float) -> None:
    """Parallel projection along -d fitted to ``pts`` (the view's width and height)."""
    right = np.cross(up, d)
    u, v = pts @ right, pts @ up
    cu, cv = 0.5 * (u.min() + u.max()), 0.5 * (v.min() + v.max())
    centre = pts.mean(0) + (cu - pts.mean(0) @ right) * right + (cv - pts.mean(0) @ up) * up
    depth = float(np.ptp(pts @ d)) + 1.0
    p.camera.focal_point = tuple(centre)
    p.camera.position = tuple(centre + 4.0 * depth * d + 10.0 * d)
    p.camera.up = tuple(up)
    p.enable_parallel_projection()
    half_h = max(0.5 * np.ptp(v), 0.5 * np.ptp(u) * size[1] / size[0], 1e-3)
    p.camera.parallel_scale = pad * half_h
    p.reset_camera_clipping_range()


def render(view: FieldView, size: tuple[int, int], direction: np.ndarray, up: np.ndarray,
           box: tuple[np.ndarray, np.ndarray] | None = None, font: int = 18) -> np.ndarray:
    """RGB image (h, w, 3) of ``view`` seen along ``-direction``; ``box`` (lo, hi) clips a close-up
    (mesh edges shown).  Raises if no OpenGL context can be made."""
    import pyvista as pv

    pv.OFF_SCREEN = True
    grid = pv.UnstructuredGrid({pv.CellType.TETRA: np.asarray(view.tets, np.int64)}, view.points)
    grid.point_data["field"] = view.values
    surf = grid.extract_surface(algorithm="dataset_surface")
    inside = (lambda x: True) if box is None else (lambda x: bool(np.all((x >= box[0]) & (x <= box[1]))))
    if box is not None:
        surf = surf.clip_box([box[0][0], box[1][0], box[0][1], box[1][1], box[0][2], box[1][2]], invert=False)
    with pv.vtk_verbosity("error"):  # VTK tries X first and warns on a headless machine
        p = pv.Plotter(off_screen=True, window_size=list(size), border=False)
    p.set_background("white")
    span = float(np.ptp(view.points, axis=0).max())
    if view.ghost is not None and box is None:
        ghost = pv.UnstructuredGrid({pv.CellType.TETRA: np.asarray(view.tets, np.int64)}, view.ghost)
        p.add_mesh(ghost.extract_feature_edges(feature_angle=40), color="#9e9e9e", line_width=1)
    p.add_mesh(surf, scalars="field", cmap=view.cmap, clim=list(view.clim), above_color=view.above,
               show_edges=box is not None, edge_color="#555555", line_width=0.4, show_scalar_bar=False)
    for tri, name in view.supports:
        patch = pv.PolyData(view.points, np.hstack([np.full((len(tri), 1), 3), tri[:, :3]]).ravel())
        rim = patch.extract_feature_edges(boundary_edges=True, feature_edges=False, manifold_edges=False,
                                          non_manifold_edges=False)
        c = view.points[np.unique(tri[:, :3])].mean(0)
        if box is not None:
            rim = rim.clip_box([box[0][0], box[1][0], box[0][1], box[1][1], box[0][2], box[1][2]], invert=False)
        if rim.n_points:
            p.add_mesh(rim, color=SUPPORT_COLOUR, line_width=4)
        if inside(c):
            s = 0.035 * span if box is None else 0.06 * float(np.max(box[1] - box[0]))
            p.add_mesh(pv.Cube(center=c, x_length=s, y_length=s, z_length=s), color=SUPPORT_COLOUR)
            p.add_point_labels(pv.PolyData(c[None, :]), [name], font_size=font - 4, text_color="white",
                               shape_color=SUPPORT_COLOUR, shape_opacity=0.8, show_points=False,
                               always_visible=True)
    big = max((float(np.linalg.norm(f)) for _, f, _ in view.arrows), default=0.0)
    for tip, f, text in view.arrows:
        n = float(np.linalg.norm(f))
        if n <= 0 or not inside(tip):
            continue
        ref = 0.18 * span if box is None else 0.45 * float(np.max(box[1] - box[0]))
        length = ref * max(n / big, 0.3)
        u = f / n
        p.add_mesh(pv.Arrow(start=tip - length * u, direction=u, scale=length, tip_length=0.3, tip_radius=0.09,
                            shaft_radius=0.035), color=LOAD_COLOUR)
        p.add_point_labels(pv.PolyData((tip - length * u)[None, :]), [text], font_size=font - 2,
                           text_color="white", shape_color=LOAD_COLOUR, shape_opacity=0.85, show_points=False,
                           always_visible=True)
    for xyz, text in view.marks:
        if inside(xyz):
            p.add_point_labels(pv.PolyData(np.asarray(xyz, float)[None, :]), [text], font_size=font, point_size=16,
                               point_color="black", render_points_as_spheres=True, shape_opacity=0.85,
                               always_visible=True)
    _fit(p, surf.points if surf.n_points else view.points, direction, up, size, 1.25 if box is None else 1.05)
    img = p.screenshot(return_img=True)
    p.close()
    return np.asarray(img)[..., :3]
