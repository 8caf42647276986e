"""Reaction histories as CSV: what ``rigfem reactions --csv`` writes and ``rigfem check --reactions-csv`` reads."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from rigfem.dynamics.history import JointHistory, ReactionHistory, singular_ranges
from rigfem.errors import InputError

# ----------------------------------------------------------------------------- CSV
_TORQUE_COLS = ("torque_Nm", "torque", "M2", "driver")


_ANGLE_COLS = ("crank_deg", "theta_deg", "angle_deg", "theta", "angle", "crank_rad", "theta_rad", "angle_rad")


def write_csv(h: ReactionHistory, path: str | Path) -> None:
    """Write the history: crank_deg, <joint>_fx_N, <joint>_fy_N, <joint>_F_N ..., torque_Nm, singular.

    Rows inside a singular range keep the crank angle but leave the force cells empty,
    so a toggle's unbounded numbers never reach a file.  Header comments (``#``) carry
    the body pairs of each joint so ``read_csv`` restores them.
    """
    mask = h.singular_mask if h.singular_mask is not None else np.zeros(h.crank_deg.size, bool)
    names = list(h.joints)
    unit = h.meta.get("driver_unit", "N·m")
    tcol = "torque_Nm" if unit == "N·m" else "driver_force_N"
    with open(path, "w", newline="") as fh:
        for n in names:
            j = h.joints[n]
            fh.write(f"# joint {n}: force by {j.body_a} on {j.body_b}\n")
        w = csv.writer(fh)
        head = ["crank_deg"]
        for n in names:
            head += [f"{n}_fx_N", f"{n}_fy_N", f"{n}_F_N"]
        w.writerow(head + [tcol, "singular"])
        for i, a in enumerate(h.crank_deg):
            row = [f"{a:.10g}"]
            for n in names:
                fx, fy = h.joints[n].force_N[i]
                row += ["", "", ""] if mask[i] else [f"{fx:.10g}", f"{fy:.10g}", f"{np.hypot(fx, fy):.10g}"]
            row.append("" if mask[i] else f"{h.torque_Nm[i]:.10g}")
            row.append("1" if mask[i] else "0")
            w.writerow(row)


def read_csv(path: str | Path) -> ReactionHistory:
    """Import a reaction history (rigfem's own CSV or an external one, e.g. from MATLAB).

    Needed columns (names case-insensitive): a crank-angle column in degrees (``crank_deg``,
    ``theta_deg``, ``angle_deg``, ``theta``, ``angle``) or radians (``crank_rad``, ``theta_rad``,
    ``angle_rad``), and per joint ``<J>_fx_N``/``<J>_fy_N`` (also ``<J>_fx``/``<J>_fy`` or
    ``<J>x``/``<J>y``) in N; optional torque column in N·m (``torque_Nm``, ``torque``, ``M2``).
    Lines starting with ``#`` are comments.  Raises InputError naming the problem.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"reaction CSV {str(p)!r} does not exist")
    pairs: dict[str, tuple[str, str]] = {}
    lines = []
    for line in p.read_text().splitlines():
        s = line.strip()
        if s.startswith("#"):
            parts = s[1:].split()
            if len(parts) >= 7 and parts[0] == "joint" and parts[2] == "force" and parts[3] == "by":
                pairs[parts[1].rstrip(":")] = (parts[4], parts[6])
        elif s:
            lines.append(line)
    if len(lines) < 2:
        raise InputError(f"reaction CSV {str(p)!r} has no data rows")
    rows = list(csv.reader(lines))
    head = [c.strip() for c in rows[0]]
    lower = [c.lower() for c in head]
    ang = next((lower.index(c) for c in _ANGLE_COLS if c in lower), None)
    if ang is None:
        raise InputError(f"reaction CSV {str(p)!r}: no crank-angle column ({', '.join(_ANGLE_COLS)})")
    data = []
    for k, r in enumerate(rows[1:], start=2):
        try:
            data.append([float(c) if c.strip() else np.nan for c in r])
        except ValueError:
            raise InputError(f"reaction CSV {str(p)!r} line {k}: non-numeric value") from None
    arr = np.array(data, float)
    if arr.ndim != 2 or arr.shape[1] != len(head):
        raise InputError(f"reaction CSV {str(p)!r}: rows do not all have {len(head)} columns")
    joints: dict[str, JointHistory] = {}
    for i, c in enumerate(lower):
        for sx, sy in (("_fx_n", "_fy_n"), ("_fx", "_fy"), ("x", "y")):
            if c.endswith(sx) and len(c) > len(sx):
                jn = head[i][: -len(sx)]
                cy = c[: -len(sx)] + sy
                if cy in lower and jn not in joints:
                    ba, bb = pairs.get(jn, ("?", "?"))
                    joints[jn] = JointHistory(jn, ba, bb, np.stack([arr[:, i], arr[:, lower.index(cy)]], -1))
                break
    if not joints:
        raise InputError(f"reaction CSV {str(p)!r}: no joint force columns (<joint>_fx_N, <joint>_fy_N)")
    tcol = next((lower.index(c.lower()) for c in _TORQUE_COLS + ("driver_force_N",) if c.lower() in lower), None)
    torque = arr[:, tcol] if tcol is not None else np.zeros(arr.shape[0])
    sing = arr[:, lower.index("singular")] > 0.5 if "singular" in lower else np.zeros(arr.shape[0], bool)
    bad = ~sing & (~np.isfinite(torque) | np.any([~np.isfinite(j.force_N).all(1) for j in joints.values()], 0))
    if np.any(bad):
        raise InputError(f"reaction CSV {str(p)!r}: empty or non-finite values at crank angle "
                         f"{arr[np.argmax(bad), ang]:g} deg")
    deg = np.degrees(arr[:, ang]) if lower[ang].endswith("_rad") else arr[:, ang]
    if not np.all(np.isfinite(deg)):
        raise InputError(f"reaction CSV {str(p)!r}: empty or non-finite crank angle")
    if np.any(np.diff(deg) <= 0):
        raise InputError(f"reaction CSV {str(p)!r}: crank angles must increase strictly")
    for j in joints.values():
        j.force_N = np.where(np.isfinite(j.force_N), j.force_N, 0.0)        # blank singular rows
    meta = {"source": str(p), "model": "imported"}
    if "driver_force_N" in head:
        meta["driver_unit"] = "N"
    h = ReactionHistory(deg, joints, np.where(np.isfinite(torque), torque, 0.0), None, meta,
                        singular_mask=sing if sing.any() else None)
    h.meta["singular"] = singular_ranges(deg, h.singular_mask)
    return h
