"""Pictures of a linkage's motion (headless matplotlib): curves over a turn and a GIF of the turn."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.animation import FuncAnimation, PillowWriter  # noqa: E402

from rigfem.files import whole_file
from rigfem.linkage.kinematics import Motion
from rigfem.rig.rules import MU_LIMITS_DEG

matplotlib.use("Agg")


#: dots per inch of the linkage GIF (10 in wide: 900 px)
GIF_DPI = 90


def _unwrapped(deg: np.ndarray) -> np.ndarray:
    return np.degrees(np.unwrap(np.radians(deg)))


def same_rotation(m: Motion) -> list[list[str]]:
    """The moving links grouped by their rotation: links that turn together (a block sliding on a
    rocker turns with it) form one group, drawn as one curve named after all of them, not as
    identical curves on top of each other."""
    groups: list[list[str]] = []
    for n in (n for n in m.links if n != "crank"):
        a = _unwrapped(m.links[n]["angle_deg"])
        for g in groups:
            b = _unwrapped(m.links[g[0]]["angle_deg"])
            if np.allclose(a - a[0], b - b[0], atol=1e-6) and abs((a[0] - b[0] + 180) % 360 - 180) < 1e-6:
                g.append(n)
                break
        else:
            groups.append([n])
    return groups


def _strokes(ax, x: np.ndarray, s: dict) -> None:
    """The slider's position over the turn, its two strokes shaded (moving +x, moving −x) with the
    crank angle each takes: a quick-return's time ratio (slow stroke / quick stroke)."""
    v = np.asarray(s["velocity_mm_s"], float)
    plus = float(np.mean(v > 0)) * 360.0
    ax.plot(x, s["position_mm"], color="tab:red")
    ax.fill_between(x, 0, 1, where=v > 0, transform=ax.get_xaxis_transform(), color="tab:blue", alpha=0.12,
                    label=f"slider moving +x ({plus:.0f}° of crank)")
    ax.fill_between(x, 0, 1, where=v <= 0, transform=ax.get_xaxis_transform(), color="tab:orange", alpha=0.12,
                    label=f"slider moving −x ({360 - plus:.0f}° of crank)")
    slow, quick = max(plus, 360.0 - plus), min(plus, 360.0 - plus)
    ax.set_title(f"slider strokes: {slow:.0f}° and {quick:.0f}° of crank, time ratio {slow / quick:.2f}"
                 if quick > 0 else "slider strokes", fontsize=10)
    ax.set_ylabel("slider position (mm)", color="tab:red")
    ax.legend(loc="best", fontsize=8)


def motion_plot(m: Motion, path: str | Path, title: str) -> Path:
    """PNG: link angles, angular velocities and accelerations, slider (if any) and the
    transmission angle with the rig's 35–145° band shaded, against the crank angle; a linkage with
    no transmission angle shows its slider's strokes there instead (a quick-return's time ratio).
    Links that turn together are one curve."""
    fig, axs = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    x = m.crank_deg
    for group in same_rotation(m):
        L, n = m.links[group[0]], " = ".join(group) + (" (turn together)" if len(group) > 1 else "")
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
    elif m.slider is not None:
        _strokes(ax, x, m.slider)
    else:
        ax.set_axis_off()
        ax.text(0.5, 0.5, "no transmission angle or slider\nfor this linkage", ha="center", va="center",
                transform=ax.transAxes, fontsize=11, color="0.4")
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
    with whole_file(path) as tmp:
        fig.savefig(tmp, dpi=90)
    plt.close(fig)
    return Path(path)


def motion_gif(m: Motion, path: str | Path, title: str, dead_deg: list[float] | None = None,
               trace: str | None = None, fps: int = 15) -> Path:
    """GIF of the linkage over the sampled crank angles: bars, the path of point ``trace``
    (the coupler point, else the slider or B) drawn whole, the transmission angle as text,
    crank positions of dead points/toggles (``dead_deg``) marked on the crank circle; every link
    and pin labelled with its name.  The GIF is 900 px wide (:data:`GIF_DPI` × 10 in)."""
    pts = {k: v["position_mm"] for k, v in m.points.items()}
    allp = np.concatenate(list(pts.values()))
    lo, hi = allp.min(0), allp.max(0)
    pad = 0.08 * max(hi - lo)
    fig, ax = plt.subplots(figsize=(10, 8))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)", fontsize=12)
    ax.set_ylabel("y (mm)", fontsize=12)
    ax.set_title(title, fontsize=12)
    ax.grid(alpha=0.3)
    trace = trace or ("P" if "P" in pts else "B")
    if trace in pts:
        ax.plot(*pts[trace].T, ":", color="tab:blue", lw=1, label=f"path of {trace}")
    if dead_deg and "A" in pts:
        r = float(np.hypot(*pts["A"][0]))
        for k, a in enumerate(dead_deg):
            ax.plot(r * np.cos(np.radians(a)), r * np.sin(np.radians(a)), "rx", ms=8,
                    label="dead point / toggle (crank)" if k == 0 else None)
    lines = {n: ax.plot([], [], "-o", lw=3, ms=6)[0] for n in m.bars}
    bar_names = {n: ax.text(0, 0, n, fontsize=12, fontweight="bold", color=lines[n].get_color(), ha="center",
                            va="bottom") for n in m.bars}
    pins = sorted({p for names in m.bars.values() for p in names})
    pin_names = {p: ax.text(0, 0, f" {p}", fontsize=12, va="top") for p in pins}
    text = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=12)
    ax.legend(loc="lower right", fontsize=10)

    def draw(i):
        for n, names in m.bars.items():
            xy = np.array([pts[p][i] for p in names])
            lines[n].set_data(xy[:, 0], xy[:, 1])
            bar_names[n].set_position(xy.mean(0))
        for p, t in pin_names.items():
            t.set_position(pts[p][i])
        t = f"crank {m.crank_deg[i]:.0f}°"
        if m.transmission_deg is not None:
            t += f"   transmission angle {m.transmission_deg[i]:.1f}°"
        text.set_text(t)
        return [*lines.values(), *bar_names.values(), *pin_names.values(), text]

    anim = FuncAnimation(fig, draw, frames=m.crank_deg.size, blit=True)
    try:
        with whole_file(path) as tmp:
            anim.save(str(tmp), writer=PillowWriter(fps=fps), dpi=GIF_DPI)
    finally:
        plt.close(fig)
    return Path(path)


def structural_error_plot(gen: dict, res: dict, path: str | Path) -> Path:
    """PNG of a function generator: ideal and generated y(x), and the structural error with the
    precision points marked."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.8))
    xp = [p["x"] for p in res["precision_points"]]
    ax1.plot(gen["x"], gen["y_ideal"], label="ideal y = " + res["expression"])
    ax1.plot(gen["x"], gen["y_generated"], "--", label="generated by the four-bar")
    ax1.plot(xp, [p["y"] for p in res["precision_points"]], "ko", label="precision points")
    ax1.set_xlabel("x")
    ax1.set_ylabel("y")
    ax1.set_title("Function and the four-bar's output")
    ax1.legend(fontsize=8)
    ax2.plot(gen["x"], gen["error"], color="tab:red")
    ax2.axhline(0, color="0.5", lw=0.8)
    ax2.plot(xp, [0] * len(xp), "ko")
    ax2.set_xlabel("x")
    ax2.set_ylabel("generated − ideal y (units of y)")
    s = res["structural_error"]
    ax2.set_title(f"Structural error (max {s['max_abs']:.3g}, {s['percent_of_range']:.2f} % of range)")
    L = res["lengths"]
    fig.suptitle(f"Four-bar function generator: a={L['a']:.4g}, b={L['b']:.4g}, c={L['c']:.4g}, d={L['d']:.4g}")
    fig.tight_layout()
    with whole_file(path) as tmp:
        fig.savefig(tmp, dpi=90)
    plt.close(fig)
    return Path(path)
