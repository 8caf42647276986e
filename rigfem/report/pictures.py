"""Pictures of a part's mesh and fields (matplotlib 3-D of the boundary triangles, headless)."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from rigfem.fe.partcase import CaseResult
from rigfem.mesh.partmesh import boundary_faces

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
    fig.savefig(path, dpi=110)
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
    a1.set_title(f"{h.meta.get('type')} {h.meta.get('lengths_mm')} ({h.meta.get('model')})", fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
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
    fig.savefig(path, dpi=110)
    plt.close(fig)
