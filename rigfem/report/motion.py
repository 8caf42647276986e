"""Pictures of a linkage's motion (headless matplotlib): curves over a turn and a GIF of the turn."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.animation import FuncAnimation, PillowWriter  # noqa: E402

from rigfem.dynamics.kinematics import Motion
from rigfem.rig.rules import MU_LIMITS_DEG

matplotlib.use("Agg")


def _unwrapped(deg: np.ndarray) -> np.ndarray:
    return np.degrees(np.unwrap(np.radians(deg)))


def motion_plot(m: Motion, path: str | Path, title: str) -> Path:
    """PNG: link angles, angular velocities and accelerations, slider (if any) and the
    transmission angle with the rig's 35–145° band shaded, against the crank angle."""
    moving = [n for n in m.links if n != "crank"]
    fig, axs = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    x = m.crank_deg
    for n in moving:
        L = m.links[n]
        axs[0, 0].plot(x, _unwrapped(L["angle_deg"]), label=n)
        axs[0, 1].plot(x, L["omega_rad_s"], label=n)
        axs[1, 0].plot(x, L["alpha_rad_s2"], label=n)
    axs[0, 0].set_ylabel("link angle (deg)")
    axs[0, 1].set_ylabel("angular velocity (rad/s)")
    axs[1, 0].set_ylabel("angular acceleration (rad/s²)")
    ax = axs[1, 1]
    if m.transmission_deg is not None:
        ax.axhspan(*MU_LIMITS_DEG, color="tab:green", alpha=0.15, label="rig band 35–145°")
        ax.plot(x, m.transmission_deg, color="k", label="transmission angle")
        ax.set_ylim(0, 180)
        ax.set_ylabel("transmission angle (deg)")
        ax.legend(loc="best", fontsize=8)
    if m.slider is not None:
        s = m.slider
        for a, key, unit in ((axs[0, 0], "position_mm", "mm"), (axs[0, 1], "velocity_mm_s", "mm/s"),
                             (axs[1, 0], "acceleration_mm_s2", "mm/s²")):
            tw = a.twinx()
            tw.plot(x, s[key], "--", color="tab:red", label=f"slider ({unit})")
            tw.set_ylabel(f"slider {key.split('_')[0]} ({unit})", color="tab:red")
    for a in axs.flat:
        a.grid(alpha=0.3)
    for a in axs[1]:
        a.set_xlabel("crank angle (deg, counter-clockwise from the ground line)")
    axs[0, 0].legend(loc="best", fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return Path(path)


def motion_gif(m: Motion, path: str | Path, title: str, dead_deg: list[float] | None = None,
               trace: str | None = None, fps: int = 15) -> Path:
    """GIF of the linkage over the sampled crank angles: bars, the path of point ``trace``
    (the coupler point, else the slider or B) drawn whole, the transmission angle as text,
    crank positions of dead points/toggles (``dead_deg``) marked on the crank circle."""
    pts = {k: v["position_mm"] for k, v in m.points.items()}
    allp = np.concatenate(list(pts.values()))
    lo, hi = allp.min(0), allp.max(0)
    pad = 0.08 * max(hi - lo)
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    trace = trace or ("P" if "P" in pts else "B")
    if trace in pts:
        ax.plot(*pts[trace].T, ":", color="tab:blue", lw=1, label=f"path of {trace}")
    if dead_deg and "A" in pts:
        r = float(np.hypot(*pts["A"][0]))
        for k, a in enumerate(dead_deg):
            ax.plot(r * np.cos(np.radians(a)), r * np.sin(np.radians(a)), "rx", ms=8,
                    label="dead point / toggle (crank)" if k == 0 else None)
    lines = {n: ax.plot([], [], "-o", lw=2, ms=3)[0] for n in m.bars}
    text = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=8)
    ax.legend(loc="lower right", fontsize=7)

    def draw(i):
        for n, names in m.bars.items():
            xy = np.array([pts[p][i] for p in names])
            lines[n].set_data(xy[:, 0], xy[:, 1])
        t = f"crank {m.crank_deg[i]:.0f}°"
        if m.transmission_deg is not None:
            t += f"   transmission angle {m.transmission_deg[i]:.1f}°"
        text.set_text(t)
        return [*lines.values(), text]

    anim = FuncAnimation(fig, draw, frames=m.crank_deg.size, blit=True)
    anim.save(str(path), writer=PillowWriter(fps=fps), dpi=70)
    plt.close(fig)
    return Path(path)
