"""Pictures of a report: each part's fields (utilisation on the report's one scale, displacement,
factor of safety), the reactions and the peaks over the crank cycle (matplotlib, headless; the
3-D views from rigfem.report.views, with a matplotlib 3-D fallback where no OpenGL runs)."""

from __future__ import annotations

import io
import textwrap
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from rigfem.fe.partcase import CaseResult, hole_forces
from rigfem.files import whole_file
from rigfem.mesh.partmesh import boundary_faces
from rigfem.report.figures import PICTURES, band, stopped_text
from rigfem.report.scale import (
    ABOVE_COLOUR,
    DISPLACEMENT_CMAP,
    UTILISATION_CMAP,
    UTILISATION_SCALE_PCT,
    colormap,
)

matplotlib.use("Agg")


def save_png(fig, path: str | Path, dpi: float) -> None:
    """``fig.savefig(path, dpi=dpi)`` as a PNG, drawn once and encoded once: RGB where every pixel
    is opaque (every picture here: the figures have an opaque background), not RGBA: the same pixels,
    a tenth smaller.  (savefig's PNG, opened and saved RGB, would encode it twice.)  Pillow's
    ``optimize=True`` would save another 2 % at four times the encoding time: not used."""
    from PIL import Image  # matplotlib's own dependency

    fig.set_dpi(dpi)
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    opaque = bool((rgba[..., 3] == 255).all())
    Image.fromarray(np.ascontiguousarray(rgba[..., :3]) if opaque else rgba).save(path, format="PNG")


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
                  view: tuple[float, float] = (30, -60), norm=None) -> Path:
    """PNG of a nodal field on the part's surface: the whole part and a close-up of its peak
    (colour limits ``norm``, default 0 to the field's peak)."""
    faces = boundary_faces(tets[:, :4])
    verts = points[faces]
    vals = values[faces].mean(axis=1)
    peak = int(np.argmax(values))
    norm = norm or plt.Normalize(0.0, float(values.max()) or 1.0)
    cmap = colormap(UTILISATION_CMAP if label.startswith(("von Mises", "factor")) else DISPLACEMENT_CMAP)
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
        save_png(fig, tmp, dpi=110)
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
        save_png(fig, tmp, dpi=120)
    plt.close(fig)


def _plot_peaks(results: list[CaseResult], limit: float, path: Path, allowable: str) -> None:
    """Peak von Mises of every part over the crank cycle (cycle mode), log scale, with the allowable."""
    fig, ax = plt.subplots(figsize=(10, 5.5))
    for r in results:
        if r.mode == "cycle":
            ax.plot(r.case.rows, r.vm_rows, label=f"{r.case.name} ({r.case.part})")
    ax.axhline(limit, color="r", ls="--", label=allowable)
    ax.set_xlabel("crank angle (°)", fontsize=12), ax.set_ylabel("peak von Mises (MPa)", fontsize=12)
    ax.set_yscale("log")
    ax.set_xlim(0, 360)
    ax.legend(fontsize=10, ncol=3)
    ax.grid(alpha=0.3)
    ax.set_title("peak von Mises stress per part over the crank cycle (cycle mode)", fontsize=13)
    fig.tight_layout()
    with whole_file(path) as tmp:
        save_png(fig, tmp, dpi=110)
    plt.close(fig)


def utilisation_plot(r: CaseResult, limit: float, path: str | Path, label: str, allowable: str) -> Path:
    """Peak von Mises of a part over the crank cycle (cycle mode) with the allowable stress."""
    fig, ax = plt.subplots(figsize=(10, 5))
    ax.plot(r.case.rows, r.vm_rows, color="#1565c0", label="peak von Mises of the part")
    ax.axhline(limit, color="#c62828", ls="--", label=allowable)
    i = int(np.argmax(r.vm_rows))
    ax.plot(r.case.rows[i], r.vm_rows[i], "o", color="k")
    ax.annotate(f"{r.vm_rows[i]:.1f} MPa at {r.case.rows[i]:.0f}° ({100 * r.vm_rows[i] / limit:.1f} %)",
                (r.case.rows[i], r.vm_rows[i]), textcoords="offset points", xytext=(8, 8), fontsize=11)
    ax.set_ylim(0, max(limit, float(r.vm_rows.max())) * 1.08)
    ax.set_xlim(0, 360)
    ax.set_xlabel("crank angle (°)", fontsize=12)
    ax.set_ylabel("peak von Mises (MPa)", fontsize=12)
    sec = ax.secondary_yaxis("right", functions=(lambda v: 100 * v / limit, lambda p: p * limit / 100))
    sec.set_ylabel("utilisation (% of the allowable)", fontsize=12)
    ax.set_title(f"{label}: peak von Mises over the crank cycle (cycle mode)", fontsize=13)
    ax.legend(loc="upper left", fontsize=10)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path = Path(path)
    with whole_file(path) as tmp:
        save_png(fig, tmp, dpi=110)
    plt.close(fig)
    return path


#: the factor of safety picture's bar: its ticks (–) where the one utilisation scale puts them (100 / FoS %)
FOS_TICKS = (1.0, 1.25, 1.5, 2.0, 3.0, 5.0)
_VERDICT_COLOUR = {"pass": "#2e7d32", "fail": "#c62828", "undecided": "#ef6c00"}


def band_lines(entry: dict, allowable: str) -> list[str]:
    """The caption's peak and band: in MPa, in % of the allowable (what the verdict reads) beside % of
    the peak, so a plate at 2 % of the allowable with ±43.7 % of its peak reads ±0.9 % of the allowable."""
    b, u = band(entry), entry["utilisation_pct"]
    return [f"peak {entry['peak_mpa']:.1f} ± {b['mpa']:.1f} MPa = utilisation {u:.1f} ± {b['pct_of_allowable']:.1f} % "
            f"({u - b['pct_of_allowable']:.1f}–{u + b['pct_of_allowable']:.1f} %) of the {allowable}",
            f"band: ±{b['mpa']:.1f} MPa = ±{b['pct_of_allowable']:.1f} % of the allowable = ±{b['pct_of_peak']:.1f} % "
            f"of the peak (error estimate, not a bound)"]


#: the longest line of a picture's legend (characters): the legend beside a rail's close-up ends inside the picture
LEGEND_CHARS = 60


def legend_text(inertia: bool, how: str) -> str:
    """The legend of a part's picture: the arrows, the supports (``how``), the markers; lines wrapped at
    :data:`LEGEND_CHARS` (a free body's support text is longer than the room beside a rail's close-up)."""
    lines = ["arrows: pin loads on the holes (N)" + (" + the part's own inertia" if inertia else ""),
             f"dark blocks: supports ({how})", "● markers: extreme values"]
    return "\n".join(textwrap.fill(line, LEGEND_CHARS, subsequent_indent="    ") for line in lines)


def _supports(r: CaseResult, fm) -> tuple[list[tuple[np.ndarray, str]], str]:
    """(triangles, label) of each held surface, and one line saying how the part is held."""
    held, how = [], []
    for kind, groups in r.case.supports:
        if kind == "free":
            how.append("free body in dynamic equilibrium (inertia relief), no support")
        for g in groups:
            if g in fm.surfaces:
                held.append((np.asarray(fm.surfaces[g]), f"held: {g}"))
        if groups:
            how.append(f"{ {'bolt': 'screws in', 'fixed': 'fixed at', 'slide': 'sliding on'}.get(kind, kind)} "
                       f"{', '.join(groups)}")
    return held, "; ".join(how)


def _bar(fig, rect, norm, cmap: str, above: str | None, label: str, ticks, fmt, top_axis=None, marks=()) -> None:
    """Horizontal colour bar; ``top_axis`` = (label, function of the value, ticks) adds a second scale."""
    cm = colormap(cmap, above)
    ax = fig.add_axes(rect)
    cb = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cm), cax=ax, orientation="horizontal",
                      extend="max" if above else "neither", ticks=ticks)
    cb.ax.set_xticklabels([fmt(t) for t in ticks], fontsize=14)
    cb.set_label(label, fontsize=15)
    for value in marks:
        ax.axvline(value, color="black", lw=4)
    if top_axis:
        name, f, tt = top_axis
        sec = ax.secondary_xaxis("top", functions=(f, lambda y: y))
        sec.set_xticks(tt)
        sec.set_xticklabels([f"{t:.0f}" if abs(t) >= 20 else f"{t:.1f}" for t in tt], fontsize=13)
        sec.set_xlabel(name, fontsize=14)


#: label boxes of each kind of annotation (views.Shot.labels): extremes, supports, pin loads
_LABEL_STYLE = {"mark": ("#f4f4f4", "black", "black"), "support": ("#202020", "none", "white"),
                "load": ("#d81b60", "none", "white")}
#: where a label may go from its point (offset points), nearest first
_OFFSETS = [(r * dx, r * dy) for r in (26, 50, 85, 130, 190)
            for dx, dy in ((1, 0.8), (-1, 0.8), (1, -0.8), (-1, -0.8), (0, 1.1), (0, -1.1), (1.2, 0), (-1.2, 0))]


def _text_box(ann, renderer):
    """Display box of an annotation's text and its rounded frame (not its leader line)."""
    from matplotlib.text import Text

    ann.update_positions(renderer)  # the text's place follows its offset only once this is done
    return Text.get_window_extent(ann, renderer).padded(6)


def _overlap(a, b) -> float:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return max(w, 0.0) * max(h, 0.0)


def _outside(a, fig_box) -> float:
    inner = _overlap(a, fig_box)
    return a.width * a.height - inner


def place_labels(fig, items, obstacles, renderer) -> list:
    """Annotations of ``items`` (axes, x, y in the axes' data, text, kind) each moved, nearest first,
    to an offset where its box overlaps no label placed before it nor an ``obstacle`` (display
    boxes: the title, the legend, the colour bar) and lies inside the figure; where none is free,
    the least bad.  ``renderer``: the figure's (its text extents; no draw is needed).  Returns the
    annotations."""
    fig_box = fig.bbox.padded(-2)
    taken, out = list(obstacles), []
    for ax, x, y, text, kind in items:
        fc, ec, colour = _LABEL_STYLE[kind]
        ann = ax.annotate(text, (x, y), xytext=(0, 0), textcoords="offset points", fontsize=13, color=colour,
                          bbox=dict(boxstyle="round,pad=0.25", fc=fc, ec=ec, alpha=0.92), annotation_clip=False,
                          arrowprops=dict(arrowstyle="-", color="black", lw=1.0, shrinkA=0, shrinkB=2), zorder=5)
        best = None
        for dx, dy in _OFFSETS:
            ann.xyann = (dx, dy)
            ann.set_ha("left" if dx > 0 else "right" if dx < 0 else "center")
            ann.set_va("bottom" if dy > 0 else "top" if dy < 0 else "center")
            box = _text_box(ann, renderer)
            cost = sum(_overlap(box, t) for t in taken) + 10.0 * _outside(box, fig_box)
            if best is None or cost < best[0]:
                best = (cost, dx, dy)
            if cost == 0:
                break
        _, dx, dy = best
        ann.xyann = (dx, dy)
        ann.set_ha("left" if dx > 0 else "right" if dx < 0 else "center")
        ann.set_va("bottom" if dy > 0 else "top" if dy < 0 else "center")
        taken.append(_text_box(ann, renderer))
        out.append(ann)
    return out


def triad(fig, rect, right: np.ndarray, up: np.ndarray, toward: np.ndarray) -> None:
    """The part frame's x, y, z axes as the views show them (parallel projection: screen right,
    screen up; an axis pointing at the viewer is ⊙, away ⊗), in the figure rectangle ``rect``."""
    ax = fig.add_axes(rect)
    ax.set_xlim(-1.45, 1.45), ax.set_ylim(-1.45, 1.45), ax.set_aspect("equal"), ax.set_axis_off()
    for k, (name, colour) in enumerate((("x", "#d32f2f"), ("y", "#2e7d32"), ("z", "#1565c0"))):
        e = np.eye(3)[k]
        a, b = float(e @ right), float(e @ up)
        if np.hypot(a, b) < 0.35:  # nearly along the line of sight
            ax.plot(0, 0, marker="o", ms=16, mfc="white", mec=colour, mew=2.5)
            ax.plot(0, 0, marker="." if e @ toward > 0 else "x", ms=10, color=colour, mew=2.5)
            ax.text(0.0, -0.45, name + (" (towards you)" if e @ toward > 0 else " (away)"), color=colour,
                    fontsize=12, fontweight="bold", ha="center", va="top")
            continue
        ax.annotate("", (a, b), (0, 0), arrowprops=dict(arrowstyle="-|>", color=colour, lw=2.5, mutation_scale=18))
        ax.text(1.22 * a, 1.22 * b, name, color=colour, fontsize=15, fontweight="bold", ha="center", va="center")
    ax.set_title("part frame (mm)", fontsize=11)


def _page(shots, elongated: bool, lines: list[str], verdict: str, legend: str, path: Path, bar,
          frame: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> list:
    """One 1600×1000 picture: the title lines, the whole part and its close-up (each image shown
    at its own pixel size, so a strip-shaped rail gets a strip), their labels placed so they do not
    overlap, the axis triad of the part frame, the colour bar.  Returns the labels' display boxes
    and texts (what the tests check)."""
    W, H = 1600, 1000
    fig = plt.figure(figsize=(W / 100, H / 100), dpi=100)
    texts = [fig.text(0.015, 0.975, lines[0], fontsize=22, fontweight="bold", va="top"),
             fig.text(0.985, 0.975, verdict.upper(), fontsize=26, fontweight="bold", va="top", ha="right",
                      color="white", bbox=dict(facecolor=_VERDICT_COLOUR.get(verdict, "#555555"), edgecolor="none",
                                               pad=6)),
             fig.text(0.015, 0.925, "\n".join(lines[1:]), fontsize=15, va="top", linespacing=1.3)]
    rects = _layout(shots, elongated)
    axes = []
    for shot, (x0, y0) in zip(shots, rects):
        h, w = shot.image.shape[:2]
        ax = fig.add_axes([x0 / W, y0 / H, w / W, h / H])
        ax.imshow(shot.image, interpolation="nearest")
        ax.set_axis_off()
        axes.append(ax)
    axes[-1].set_title("close-up of the peak, mesh edges shown", fontsize=14)
    lx, ly = (rects[1][0] + shots[1].image.shape[1] + 30, 185) if elongated else (975, 185)
    texts.append(fig.text(lx / W, ly / H, legend, fontsize=13, va="bottom"))
    if frame is not None:
        x0, y0 = (W - 260, 265) if elongated else (rects[1][0] + shots[1].image.shape[1] + 10, 420)
        triad(fig, [x0 / W, y0 / H, 170 / W, 170 / H], *frame)
    bar(fig)
    renderer = fig.canvas.get_renderer()  # text extents and layout, without drawing the page (save_png draws it once)
    obstacles = [t.get_window_extent(renderer) for t in texts] + [axes[-1].title.get_window_extent(renderer)]
    obstacles += [a.get_tightbbox(renderer) for a in fig.axes if a not in axes]
    anns = place_labels(fig, [(ax, x, y, text, kind) for ax, shot in zip(axes, shots)
                              for x, y, text, kind in shot.labels], obstacles, renderer)
    boxes = [(a.get_text(), _text_box(a, renderer)) for a in anns]
    save_png(fig, path, dpi=100)
    plt.close(fig)
    return boxes


#: the page's panels (figure pixels, y up): the whole part's top edge, the close-up's, the space they share
_TOP, _BOTTOM, _GAP = 790, 175, 60


def _layout(shots, elongated: bool) -> list[tuple[int, int]]:
    """Lower-left corners (figure pixels) of the whole part's view and of the close-up: a long part
    as a full-width strip under the title with its close-up below; a compact one beside its close-up."""
    (h0, w0), (h1, _) = shots[0].image.shape[:2], shots[1].image.shape[:2]
    if elongated:
        y0 = _TOP - _GAP // 2 - h0
        return [(int((1600 - w0) / 2), y0), (20, _BOTTOM + max(0, (y0 - _GAP - _BOTTOM - h1) // 2))]
    return [(10, _BOTTOM + 5 + max(0, (_TOP - 20 - _BOTTOM - 5 - h0) // 2)), (970, _TOP - 40 - h1)]


def part_pictures(r: CaseResult, c: np.ndarray, entry: dict, limit: float, label: str, allowable: str,
                  folder: str | Path, zoom_mm: float = 30.0, kinds: tuple[str, ...] = PICTURES,
                  stem: str | None = None) -> dict:
    """The pictures ``kinds`` of a part at its critical crank angle: utilisation of the allowable (von
    Mises) on the report's one scale :data:`UTILISATION_SCALE_PCT`, displacement magnitude, factor of safety;
    files ``<stem>.png`` (von Mises) and ``<stem>_<kind>.png`` (``stem`` default: the part's name).

    Each states the part ``label``, its verdict, utilisation ± band, mode and crank angle, marks the
    extremes with values, draws the pin loads (N) and the supports.  Returns what was drawn: the file
    names, the scale (for report.json) and the renderer.
    """
    from rigfem.report.vtu import SAFETY_CAP
    from rigfem.report.views import FieldView, framing, render

    folder = Path(folder)
    fm, sol = r.solution.model.mesh, r.solution
    vm, u = sol.von_mises(c), sol.displacement(c)
    tets = np.asarray(fm.elements[:, :4])
    n = fm.n_vertices
    umag = np.linalg.norm(u, axis=1)
    span = float(np.ptp(fm.nodes, axis=0).max())
    scale = _nice(0.04 * span / umag.max()) if umag.max() > 0 else 1.0
    x = fm.nodes + scale * u
    pct = 100.0 * vm / limit
    fos = np.minimum(limit / np.maximum(vm, limit / SAFETY_CAP), SAFETY_CAP)
    on_surf = np.unique(boundary_faces(tets))
    hi, lo = int(np.argmax(vm)), int(on_surf[np.argmin(vm[on_surf])])
    nb = tets[(np.asarray(fm.elements) == hi).any(1)]
    normal = x[hi] - x[nb].reshape(-1, 3).mean(0)
    d, up, elongated = framing(x[:n], x[hi], normal / (np.linalg.norm(normal) or 1.0))
    loads = [(x[nodes].mean(0), f, f"{g}: {np.linalg.norm(f):.0f} N") for g, nodes, f in hole_forces(r, c)]
    held, how = _supports(r, fm)
    inertia = any(ld.kind != "bearing" for ld in r.case.loads)
    deg = float(r.case.rows[r.row])
    head = [f"{label}: {{what}}",
            f"{r.mode} mode, crank angle {deg:.1f}°; deformation ×{scale:g}; mesh "
            f"{(entry.get('mesh') or {}).get('level') or '–'}, refining stopped: {stopped_text(entry)}",
            *band_lines(entry, allowable)]
    legend = legend_text(inertia, how)
    box = (x[hi] - zoom_mm, x[hi] + zoom_mm)
    w_h = {True: [(1560, 300), (980, 0)], False: [(940, 590), (430, 420)]}[elongated]
    base = dict(points=x[:n], tets=tets, arrows=loads, supports=held)
    util_bar = dict(norm=plt.Normalize(*UTILISATION_SCALE_PCT), cmap=UTILISATION_CMAP, above=ABOVE_COLOUR)
    pics = {
        "von_mises": (FieldView(values=pct[:n], clim=UTILISATION_SCALE_PCT, cmap=colormap(), above=ABOVE_COLOUR,
                                marks=[(x[hi], f"max {vm[hi]:.1f} MPa ({pct[hi]:.1f} %)"),
                                       (x[lo], f"min {vm[lo]:.2g} MPa")], **base),
                      "von Mises stress, as utilisation",
                      lambda f: _bar(f, [0.12, 0.055, 0.76, 0.03], **util_bar,
                                     label=f"utilisation = von Mises / {allowable} (%); above 100 %: "
                                     f"magenta; black line: this part's peak {pct[hi]:.1f} %",
                                     ticks=[0, 20, 40, 60, 80, 100], fmt=lambda t: f"{t:.0f} %",
                                     top_axis=("von Mises (MPa)", lambda p: p * limit / 100, np.linspace(0, limit, 6)),
                                     marks=[min(pct[hi], 100.0)])),
        "displacement": (FieldView(values=umag[:n], clim=(0.0, float(umag.max()) or 1.0),
                                   cmap=colormap(DISPLACEMENT_CMAP, None), above=None,
                                   marks=[(x[int(np.argmax(umag))], f"max {umag.max():.3g} mm")],
                                   ghost=fm.nodes[:n], **base),
                         "displacement magnitude (grey: undeformed)",
                         lambda f: _bar(f, [0.12, 0.07, 0.76, 0.03], plt.Normalize(0, float(umag.max()) or 1.0),
                                        DISPLACEMENT_CMAP, None, "displacement magnitude (mm)",
                                        np.linspace(0, float(umag.max()) or 1.0, 6), lambda t: f"{t:.3g}")),
        # the factor of safety coloured as its utilisation (100 / FoS %) on the one scale: the same colour
        # means the same thing in every picture; the bar reads the factor of safety
        "safety_factor": (FieldView(values=pct[:n], clim=UTILISATION_SCALE_PCT, cmap=colormap(), above=ABOVE_COLOUR,
                                    marks=[(x[hi], f"min {fos[hi]:.2f}")], **base),
                          "factor of safety",
                          lambda f: _bar(f, [0.12, 0.07, 0.76, 0.03], **util_bar,
                                         label=f"factor of safety = {allowable.split(' =')[0]} / von Mises (–), on the "
                                         f"utilisation scale (100 % / factor); black line: 1; below 1: magenta",
                                         ticks=[100.0 / t for t in FOS_TICKS], fmt=lambda t: f"{100.0 / t:.3g}",
                                         marks=[100.0])),
    }
    files, stem = {}, stem or r.case.name
    for key, (view, what, bar) in ((k, pics[k]) for k in kinds):
        name = f"{stem}.png" if key == "von_mises" else f"{stem}_{key}.png"
        try:
            whole = render(view, w_h[0], d, up, shrink=elongated)
            size = w_h[1] if not elongated else (980, _TOP - _GAP * 2 - whole.image.shape[0] - _BOTTOM)
            shots = [whole, render(view, size, d, up, box, shrink=elongated)]
        except Exception:  # noqa: BLE001 - no OpenGL context on this machine: the simpler picture
            field_picture(fm.nodes, fm.elements, view.values, folder / name, f"{label}: {what}", what,
                          norm=plt.Normalize(*view.clim))
            files[key], renderer = name, "matplotlib"
            continue
        lines = [head[0].format(what=what), *head[1:]]
        _page(shots, elongated, lines, entry["verdict"], legend, folder / name, bar, (whole.right, whole.up, d))
        files[key], renderer = name, "pyvista"
    return {"files": files, "renderer": renderer, "deformation_scale": scale,
            "utilisation_scale_pct": list(UTILISATION_SCALE_PCT), "utilisation_scale_mpa": [0.0, limit],
            # the factor of safety is coloured as 100 / FoS % on the one scale: 1 at its top, none at 0 %
            "safety_factor_scale": [1.0, None], "displacement_scale_mm": [0.0, float(umag.max())]}


def _nice(x: float) -> float:
    """x rounded down to 1, 2 or 5 × a power of ten."""
    e = 10.0 ** np.floor(np.log10(x))
    return float(max(m for m in (1.0, 2.0, 5.0) if m * e <= x) * e) if x > 0 else 1.0
