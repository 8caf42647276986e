"""Pictures of a report: each part's fields (utilisation on the report's one scale, displacement,
factor of safety), the reactions and the peaks over the crank cycle (matplotlib, headless; the
3-D views from rigfem.report.views, with a matplotlib 3-D fallback where no OpenGL runs)."""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from rigfem.fe.partcase import CaseResult
from rigfem.files import whole_file
from rigfem.mesh.partmesh import boundary_faces

matplotlib.use("Agg")


def save_png(fig, path: str | Path, dpi: float) -> None:
    """``fig.savefig(path, dpi=dpi)`` as a PNG, but RGB where every pixel is opaque (every picture
    here: the figures have an opaque background), not RGBA: the same pixels, a tenth smaller.
    Pillow's ``optimize=True`` would save another 2 % at four times the encoding time: not used."""
    from PIL import Image  # matplotlib's own dependency

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    buf.seek(0)
    with Image.open(buf) as im:
        im.load()
        if im.mode == "RGBA" and im.getextrema()[3] == (255, 255):
            im = im.convert("RGB")
        im.save(path, format="PNG")


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


#: the ONE colour scale of every part's stress picture in a report: utilisation, % of the allowable
UTILISATION_SCALE_PCT = (0.0, 100.0)
#: colour of a utilisation above 100 % (beyond the allowable) and of a factor of safety above FOS_TOP
ABOVE_COLOUR, FOS_TOP = "#ff00ff", 5.0
_VERDICT_COLOUR = {"pass": "#2e7d32", "fail": "#c62828", "undecided": "#ef6c00"}


def _pin_loads(r: CaseResult, c: np.ndarray, fm, x: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """(tip, force N, label) of each loaded hole: the applied nodal forces summed over the hole."""
    F = r.solution.loads(c).reshape(-1, 3)
    out = []
    for g in dict.fromkeys(ld.group for ld in r.case.loads if ld.kind == "bearing" and ld.group):
        nodes = np.unique(fm.surfaces[g]) if g in fm.surfaces else np.zeros(0, int)
        f = F[nodes].sum(0)
        if len(nodes) and np.linalg.norm(f) > 0:
            out.append((x[nodes].mean(0), f, f"{g}: {np.linalg.norm(f):.0f} N"))
    return out


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
    cm = plt.get_cmap(cmap).with_extremes(over=above) if above else plt.get_cmap(cmap)
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


def _page(images, elongated: bool, lines: list[str], verdict: str, legend: str, path: Path, bar) -> None:
    """One 1600×1000 picture: the title lines, the whole part and its close-up, the colour bar."""
    fig = plt.figure(figsize=(16, 10), dpi=100)
    fig.text(0.015, 0.975, lines[0], fontsize=22, fontweight="bold", va="top")
    fig.text(0.985, 0.975, verdict.upper(), fontsize=26, fontweight="bold", va="top", ha="right", color="white",
             bbox=dict(facecolor=_VERDICT_COLOUR.get(verdict, "#555555"), edgecolor="none", pad=6))
    fig.text(0.015, 0.925, "\n".join(lines[1:]), fontsize=16, va="top", linespacing=1.35)
    for img, rect in zip(images, _RECTS[elongated]):
        ax = fig.add_axes(rect)
        ax.imshow(img)
        ax.set_axis_off()
    fig.axes[-1].set_title("close-up of the peak, mesh edges shown", fontsize=14)
    fig.text(*(_RECTS[elongated][2][:2] if elongated else (0.015, 0.155)), legend, fontsize=14, va="bottom")
    bar(fig)
    save_png(fig, path, dpi=100)
    plt.close(fig)


#: axes rectangles (figure fractions): whole part, close-up, legend corner; long parts vs compact ones
_RECTS = {True: ([0.01, 0.50, 0.98, 0.31], [0.01, 0.17, 0.48, 0.30], [0.52, 0.20]),
          False: ([0.01, 0.19, 0.58, 0.62], [0.60, 0.19, 0.39, 0.58], None)}


def part_pictures(r: CaseResult, c: np.ndarray, entry: dict, limit: float, label: str, allowable: str,
                  folder: str | Path, zoom_mm: float = 30.0) -> dict:
    """Three pictures of a part at its critical crank angle: utilisation of the allowable (von Mises) on
    the report's one scale :data:`UTILISATION_SCALE_PCT`, displacement magnitude, factor of safety.

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
    loads = _pin_loads(r, c, fm, x)
    held, how = _supports(r, fm)
    inertia = any(ld.kind != "bearing" for ld in r.case.loads)
    deg = float(r.case.rows[r.row])
    u_pct, e = entry["utilisation_pct"], entry["error_pct"]
    head = [f"{label}: {{what}}",
            f"{r.mode} mode, crank angle {deg:.1f}°; deformation ×{scale:g}",
            f"peak {vm[hi]:.1f} MPa ± {e:.1f} % = utilisation {u_pct:.1f} % ({u_pct * (1 - e / 100):.1f}–"
            f"{u_pct * (1 + e / 100):.1f} %) of the {allowable}"]
    legend = ("arrows: pin loads on the holes (N)" + (" + the part's own inertia" if inertia else "")
              + f"\ndark blocks: supports ({how})\n● markers: extreme values")
    box = (x[hi] - zoom_mm, x[hi] + zoom_mm)
    w_h = {True: [(1568, 310), (768, 300)], False: [(928, 620), (624, 580)]}[elongated]
    base = dict(points=x[:n], tets=tets, arrows=loads, supports=held)
    pics = {
        "von_mises": (FieldView(values=pct[:n], clim=UTILISATION_SCALE_PCT, cmap="turbo", above=ABOVE_COLOUR,
                                marks=[(x[hi], f"max {vm[hi]:.1f} MPa ({pct[hi]:.1f} %)"),
                                       (x[lo], f"min {vm[lo]:.2g} MPa")], **base),
                      "von Mises stress, as utilisation",
                      lambda f: _bar(f, [0.12, 0.055, 0.76, 0.03], plt.Normalize(*UTILISATION_SCALE_PCT), "turbo",
                                     ABOVE_COLOUR, f"utilisation = von Mises / {allowable} (%); above 100 %: "
                                     f"magenta; black line: this part's peak {pct[hi]:.1f} %",
                                     [0, 20, 40, 60, 80, 100], lambda t: f"{t:.0f} %",
                                     ("von Mises (MPa)", lambda p: p * limit / 100, np.linspace(0, limit, 6)),
                                     [min(pct[hi], 100.0)])),
        "displacement": (FieldView(values=umag[:n], clim=(0.0, float(umag.max()) or 1.0), cmap="viridis",
                                   above=None, marks=[(x[int(np.argmax(umag))], f"max {umag.max():.3g} mm")],
                                   ghost=fm.nodes[:n], **base),
                         "displacement magnitude (grey: undeformed)",
                         lambda f: _bar(f, [0.12, 0.07, 0.76, 0.03], plt.Normalize(0, float(umag.max()) or 1.0),
                                        "viridis", None, "displacement magnitude (mm)",
                                        np.linspace(0, float(umag.max()) or 1.0, 6), lambda t: f"{t:.3g}")),
        "safety_factor": (FieldView(values=fos[:n], clim=(0.0, FOS_TOP), cmap="RdYlGn", above="#00441b",
                                    marks=[(x[hi], f"min {fos[hi]:.2f}")], **base),
                          "factor of safety",
                          lambda f: _bar(f, [0.12, 0.07, 0.76, 0.03], plt.Normalize(0, FOS_TOP), "RdYlGn", "#00441b",
                                         f"factor of safety = {allowable.split(' =')[0]} / von Mises (–), black line: 1; above "
                                         f"{FOS_TOP:g}: dark green (capped at {SAFETY_CAP:g})",
                                         [0, 1, 2, 3, 4, 5], lambda t: f"{t:.0f}",
                                         marks=[1.0])),
    }
    files = {}
    for key, (view, what, bar) in pics.items():
        name = f"{r.case.name}.png" if key == "von_mises" else f"{r.case.name}_{key}.png"
        try:
            images = [render(view, w_h[0], d, up), render(view, w_h[1], d, up, box)]
        except Exception:  # noqa: BLE001 - no OpenGL context on this machine: the simpler picture
            field_picture(fm.nodes, fm.elements, view.values, folder / name, f"{label}: {what}", what,
                          norm=plt.Normalize(*view.clim))
            files[key], renderer = name, "matplotlib"
            continue
        lines = [head[0].format(what=what), *head[1:]]
        _page(images, elongated, lines, entry["verdict"], legend, folder / name, bar)
        files[key], renderer = name, "pyvista"
    return {"files": files, "renderer": renderer, "deformation_scale": scale,
            "utilisation_scale_pct": list(UTILISATION_SCALE_PCT), "utilisation_scale_mpa": [0.0, limit],
            "safety_factor_scale": [0.0, FOS_TOP], "displacement_scale_mm": [0.0, float(umag.max())]}


def _nice(x: float) -> float:
    """x rounded down to 1, 2 or 5 × a power of ten."""
    e = 10.0 ** np.floor(np.log10(x))
    return float(max(m for m in (1.0, 2.0, 5.0) if m * e <= x) * e) if x > 0 else 1.0
