"""3-D views of a part's nodal field for the report's pictures (PyVista, off-screen).

The camera frames the part so its stressed region shows: the part's long axis lies
horizontal on the screen, a flat part is seen nearly face-on, a long part (a rail) nearly
square to the face that carries its peak, and the projection is parallel and fitted to the
part's own extent (a long rail fills the width instead of being a thin diagonal).  Marked
points are black dots, pin loads are arrows, supports are dark blocks with their outline.
Each view is returned as a :class:`Shot`: the RGB image, the projection of the part frame to its
pixels and the texts to write at projected points (values, forces in N, support names), so the
caller composes the page (labels that do not overlap, axis triad, title, colour bar) with
matplotlib.
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
    cmap: object  #: a matplotlib colour map (rigfem.report.scale.colormap) or its name
    above: str | None  #: colour above clim[1] (None: the colour map's top)
    marks: list[tuple[np.ndarray, str]] = field(default_factory=list)  #: (xyz, text) markers
    arrows: list[tuple[np.ndarray, np.ndarray, str]] = field(default_factory=list)  #: (tip, force N, text)
    supports: list[tuple[np.ndarray, str]] = field(default_factory=list)  #: (triangles (K, 3), name)
    ghost: np.ndarray | None = None  #: undeformed node positions, drawn as a faint outline


@dataclass
class Shot:
    """One rendered view: the image, its parallel projection (part frame, mm -> pixels, y down)
    and the labels to write, each (pixel x, pixel y, text, kind: ``mark``, ``support`` or ``load``)."""

    image: np.ndarray
    centre: np.ndarray  #: the part-frame point at the image's centre
    right: np.ndarray  #: unit vector of the part frame along the image's +x (pixels to the right)
    up: np.ndarray  #: unit vector along the image's up (-y in pixels)
    px_per_mm: float
    labels: list[tuple[float, float, str, str]] = field(default_factory=list)

    def pixel(self, xyz) -> tuple[float, float]:
        """Pixel (x right, y down) of a part-frame point."""
        h, w = self.image.shape[:2]
        r = np.asarray(xyz, float) - self.centre
        return 0.5 * w + float(r @ self.right) * self.px_per_mm, 0.5 * h - float(r @ self.up) * self.px_per_mm


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
    elif ext[0] > 3.0 * ext[1]:  # a long part: nearly square to the side face that carries the peak
        face = max((e2, -e2, e3, -e3), key=lambda f: float(normal @ f))
        other = e3 if abs(face @ e2) > 0.5 else e2
        d = face + 0.3 * other * (1.0 if other[2] >= 0 else -1.0)
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


def projected_aspect(points: np.ndarray, d: np.ndarray, up: np.ndarray) -> float:
    """Height / width of ``points`` seen along -d with ``up`` up (a long rail: small)."""
    right = np.cross(up, d)
    return float(np.ptp(points @ up)) / max(float(np.ptp(points @ right)), 1e-9)


def _fit(p, pts: np.ndarray, d: np.ndarray, up: np.ndarray, size: tuple[int, int], pad: float):
    """Parallel projection along -d fitted to ``pts`` (the view's width and height); returns the
    centre, the screen's right and up, and the pixels per mm."""
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
    return centre, right, up, 0.5 * size[1] / (pad * half_h)


def render(view: FieldView, size: tuple[int, int], direction: np.ndarray, up: np.ndarray,
           box: tuple[np.ndarray, np.ndarray] | None = None, shrink: bool = False) -> Shot:
    """:class:`Shot` of ``view`` seen along ``-direction`` (image (h, w, 3)); ``box`` (lo, hi) clips a
    close-up (mesh edges shown).  The labels are returned, not drawn: the page places them so they
    do not overlap.  Every support is drawn (its outline, and a block at its centre when the centre
    is in the view).  ``shrink``: the image's height is cut to what the part needs at the image's
    width (a long rail: a strip the part fills, not a tall picture with the rail a sliver in it).
    Raises if no OpenGL context can be made."""
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
    second = float(np.sort(np.ptp(view.points, axis=0))[1])  # a long part's arrows: of its section's size
    if view.ghost is not None and box is None:
        ghost = pv.UnstructuredGrid({pv.CellType.TETRA: np.asarray(view.tets, np.int64)}, view.ghost)
        p.add_mesh(ghost.extract_feature_edges(feature_angle=40), color="#9e9e9e", line_width=1)
    p.add_mesh(surf, scalars="field", cmap=view.cmap, clim=list(view.clim), above_color=view.above,
               show_edges=box is not None, edge_color="#555555", line_width=0.4, show_scalar_bar=False)
    labels: list[tuple[np.ndarray, str, str]] = []
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
            labels.append((c, name, "support"))
    tails: list[np.ndarray] = []
    big = max((float(np.linalg.norm(f)) for _, f, _ in view.arrows), default=0.0)
    for tip, f, text in view.arrows:
        n = float(np.linalg.norm(f))
        if n <= 0 or not inside(tip):
            continue
        ref = min(0.18 * span, 1.2 * second) if box is None else 0.45 * float(np.max(box[1] - box[0]))
        length = ref * max(n / big, 0.3)
        u = f / n
        p.add_mesh(pv.Arrow(start=tip - length * u, direction=u, scale=length, tip_length=0.3, tip_radius=0.09,
                            shaft_radius=0.035), color=LOAD_COLOUR)
        labels.append((tip - length * u, text, "load"))
        tails.append(tip - length * u)
    marked: list[tuple[np.ndarray, str, str]] = []
    for xyz, text in view.marks:
        if inside(xyz):
            p.add_points(np.asarray(xyz, float)[None, :], color="black", point_size=16, render_points_as_spheres=True)
            marked.append((np.asarray(xyz, float), text, "mark"))
    labels = marked + labels  # the extremes placed first
    fitted = np.vstack([surf.points if surf.n_points else view.points, *[t[None, :] for t in tails]])
    if shrink:
        pad = 1.12
        size = (size[0], int(min(size[1], max(80, round(size[0] * projected_aspect(fitted, direction, up) * pad)))))
        p.window_size = list(size)
    centre, right, screen_up, scale = _fit(p, fitted, direction, up, size, 1.12 if box is None else 1.05)
    img = np.asarray(p.screenshot(return_img=True))[..., :3]
    p.close()
    shot = Shot(img, np.asarray(centre, float), right, screen_up, scale)
    shot.labels = [(*shot.pixel(xyz), text, kind) for xyz, text, kind in labels]
    return shot
