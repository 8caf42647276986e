"""Reaction histories as CSV: what ``rigfem reactions --csv`` writes and ``rigfem check --reactions-csv`` reads."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from rigfem.dynamics.history import JointHistory, ReactionHistory
from rigfem.errors import InputError, decode_text, plain, read_at_most
from rigfem.files import whole_file
from rigfem.linkage.loops import is_full_turn, singular_ranges

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
    with whole_file(path) as tmp, open(tmp, "w", newline="") as fh:
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


#: largest reaction CSV read (bytes): rigfem's own CSV of 100 000 crank angles (the most a check
#: samples) is about 25 MB
MAX_BYTES = 64 * 2**20


#: largest crank-angle step (deg) an imported history may have: 36 samples per turn, the least
#: rigfem's own dynamics accepts ([check].samples)
MAX_STEP_DEG = 10.0


#: largest gap (% of the peak force) between the cubic and the linear estimate of a force
#: half-way between two samples: above it the sampling does not resolve the curve
MAX_MIDPOINT_PCT = 5.0


#: largest share of rows marked singular (or blank): beyond it the history is mostly unknown and the
#: peak search would rest on the few rows left (a CSV of 359 blank singular rows of 360 read PASS)
MAX_SINGULAR_SHARE = 0.05


#: the largest joint force of a real rig linkage (N): below MIN it is not in N (kN?): the
#: lightest rig crank (a 700 mm rail, 1.9 kg, at 1 Hz) already carries ~15 N; above MAX it is not
#: a rig linkage that meets the rig rules (a toggle, or the wrong unit)
FORCE_RANGE_N = (5.0, 1e6)


def _check_turn(where: str, column: str, raw: np.ndarray, deg: np.ndarray) -> None:
    """The crank angles span one full turn (no more) in steps of at most MAX_STEP_DEG, in the
    unit the column declares (a ``*_deg`` column spanning at most 2π looks like radians)."""
    span = float(deg[-1] - deg[0])
    raw_span = float(raw[-1] - raw[0])
    if not column.lower().endswith("_rad") and raw_span <= 2 * np.pi + 1e-6 and raw.size > 3:
        raise InputError(f"reaction CSV {where!r}: column {column} spans {raw_span:.4g}, at most 2π: the angles look "
                         f"like radians; name the column crank_rad or give degrees")
    if column.lower().endswith("_rad") and raw_span > 2 * np.pi + 1e-6:
        raise InputError(f"reaction CSV {where!r}: column {column} spans {raw_span:.4g} rad, more than one turn (2π): "
                         f"the angles look like degrees; name the column crank_deg")
    if span >= 360.0 - 1e-9 * 360 and not np.isclose(span, 360.0):
        raise InputError(f"reaction CSV {where!r}: crank angles span {span:g} deg, more than one turn (360 deg)")
    gaps = np.append(np.diff(deg), 360.0 - span)  # the last gap closes the turn
    worst = int(np.argmax(gaps))
    if gaps[worst] > MAX_STEP_DEG + 1e-9:
        at = deg[worst] if worst < deg.size - 1 else deg[-1]
        raise InputError(f"reaction CSV {where!r}: does not cover a full turn in steps of at most {MAX_STEP_DEG:g} deg "
                         f"(a gap of {gaps[worst]:.4g} deg after crank {at:g} deg; angles span {deg[0]:g}..{deg[-1]:g} deg)")


def _check_forces(where: str, deg: np.ndarray, forces: dict[str, np.ndarray], sing: np.ndarray) -> None:
    """Force magnitudes in N and sampled finely enough to bracket their peaks.

    Why this rule: a peak read from samples (refined on a spline) is only right when the
    samples resolve the curve.  Half-way between two samples the cubic estimate
    (-f[i-1] + 9 f[i] + 9 f[i+1] - f[i+2]) / 16 and the linear one (f[i] + f[i+1]) / 2
    differ by (-f[i-1] + f[i] + f[i+1] - f[i+2]) / 16, the local curvature times the step²;
    when that exceeds MAX_MIDPOINT_PCT of the peak the samples straddle a peak they do not
    resolve (the issue's example, 12 samples per turn, read 290 N for a 472 N peak).  For a
    resolved history (rigfem's 360 samples) it is below 0.01 %.
    """
    ok = ~sing
    mags = {n: np.hypot(f[:, 0], f[:, 1]) for n, f in forces.items()}
    peak = max((float(np.max(m[ok])) for m in mags.values() if ok.any()), default=0.0)
    lo, hi = FORCE_RANGE_N
    if peak < lo:
        raise InputError(f"reaction CSV {where!r}: largest joint force {peak:.4g} N is below {lo:g} N: "
                         f"forces must be in N (kN given?)")
    if peak > hi:
        raise InputError(f"reaction CSV {where!r}: largest joint force {peak:.4g} N is above {hi:g} N: "
                         f"forces must be in N and the history bounded")
    s = np.concatenate([sing[-1:], sing, sing[:2]])
    usable = ~(s[:-3] | s[1:-2] | s[2:-1] | s[3:])  # windows of four rows, none singular (around a toggle
    for n, m in mags.items():                      # the curve is not meant to be smooth)
        f = np.concatenate([m[-1:], m, m[:2]])  # one turn, closed
        gap = np.where(usable, np.abs(-f[:-3] + f[1:-2] + f[2:-1] - f[3:]) / 16.0, 0.0)
        k = int(np.argmax(gap))
        if gap[k] > MAX_MIDPOINT_PCT / 100 * peak:
            raise InputError(f"reaction CSV {where!r}: joint {n} is sampled too coarsely to bracket its peaks "
                             f"(between crank {deg[k]:g} deg and the next sample the force curve is not resolved: "
                             f"{100 * gap[k] / peak:.2g} % of the peak > {MAX_MIDPOINT_PCT:g} %); give more crank angles")


def read_csv(path: str | Path, missing: dict[str, float] | None = None,
             linkage_joints: tuple[str, ...] | None = None) -> ReactionHistory:
    """Import a reaction history (rigfem's own CSV or an external one, e.g. from MATLAB).

    Needed columns (names case-insensitive): a crank-angle column in degrees (``crank_deg``,
    ``theta_deg``, ``angle_deg``, ``theta``, ``angle``) or radians (``crank_rad``, ``theta_rad``,
    ``angle_rad``), and per joint ``<J>_fx_N``/``<J>_fy_N`` (also ``<J>_fx``/``<J>_fy`` or
    ``<J>x``/``<J>y``) in N; the driver torque in N·m (``torque_Nm``, ``torque``, ``M2``,
    ``driver``) or driver force in N (``driver_force_N``).  A CSV without the driver column is
    refused (a torque read as zero unloads the crank) unless ``missing`` states its value, e.g.
    ``{"torque_Nm": 0.0}`` (``[check].reactions_csv_missing``); the history's
    ``meta["assumed"]`` then says so.  Lines starting with ``#`` are comments.  Refused
    (InputError naming the problem): angles that do not cover one full turn in steps of at most
    :data:`MAX_STEP_DEG`, angles or forces that do not fit their declared unit (radians in a
    degree column, kN), sampling too coarse to bracket the peaks (see :func:`_check_forces`; rows
    marked singular are left out of that test, not the test itself), more than
    :data:`MAX_SINGULAR_SHARE` of the rows marked singular, and a column (or a joint's pair, the
    driver, the crank angle) given twice.  With ``linkage_joints`` (the scene's linkage's joint
    names), a CSV without one of those joints is refused too.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"reaction CSV {str(p)!r} does not exist")
    pairs: dict[str, tuple[str, str]] = {}
    lines = []
    blob = read_at_most(p, MAX_BYTES, f"reaction CSV {str(p)!r}", "a reaction CSV")
    for line in decode_text(blob, f"reaction CSV {str(p)!r}").splitlines():
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
    twice = sorted({c for c in lower if lower.count(c) > 1})
    if twice:
        raise InputError(f"reaction CSV {str(p)!r}: column {head[lower.index(twice[0])]} appears "
                         f"{lower.count(twice[0])} times; which one holds the data is ambiguous: keep one")
    angles = [head[i] for i, c in enumerate(lower) if c in _ANGLE_COLS]
    if len(angles) > 1:
        raise InputError(f"reaction CSV {str(p)!r}: {len(angles)} crank-angle columns ({', '.join(angles)}); "
                         f"which one is the crank's is ambiguous: keep one")
    ang = next((lower.index(c) for c in _ANGLE_COLS if c in lower), None)
    if ang is None:
        raise InputError(f"reaction CSV {str(p)!r}: no crank-angle column ({', '.join(_ANGLE_COLS)})")
    data = []
    for k, r in enumerate(rows[1:], start=2):
        try:
            data.append([float(c) if c.strip() else np.nan for c in r])
        except ValueError:
            raise InputError(f"reaction CSV {str(p)!r} line {k}: non-numeric value") from None
    if any(len(r) != len(head) for r in data):
        raise InputError(f"reaction CSV {str(p)!r}: rows do not all have {len(head)} columns")
    arr = np.array(data, float)
    if arr.ndim != 2 or arr.shape[1] != len(head):
        raise InputError(f"reaction CSV {str(p)!r}: rows do not all have {len(head)} columns")
    joints: dict[str, JointHistory] = {}
    for i, c in enumerate(lower):
        for sx, sy in (("_fx_n", "_fy_n"), ("_fx", "_fy"), ("x", "y")):
            if c.endswith(sx) and len(c) > len(sx):
                jn = head[i][: -len(sx)]
                cy = c[: -len(sx)] + sy
                if cy in lower and jn in joints:
                    raise InputError(f"reaction CSV {str(p)!r}: joint {jn} has two pairs of force columns; "
                                     f"which one holds its force is ambiguous: keep one")
                if cy in lower:
                    ba, bb = pairs.get(jn, ("?", "?"))
                    joints[jn] = JointHistory(jn, ba, bb, np.stack([arr[:, i], arr[:, lower.index(cy)]], -1))
                break
    if not joints:
        raise InputError(f"reaction CSV {str(p)!r}: no joint force columns (<joint>_fx_N, <joint>_fy_N)")
    torques = [head[i] for i, c in enumerate(lower) if c in {t.lower() for t in _TORQUE_COLS + ("driver_force_N",)}]
    if len(torques) > 1:
        raise InputError(f"reaction CSV {str(p)!r}: {len(torques)} driver columns ({', '.join(torques)}); "
                         f"which one loads the crank is ambiguous: keep one")
    tcol = next((lower.index(c.lower()) for c in _TORQUE_COLS + ("driver_force_N",) if c.lower() in lower), None)
    stated = (missing or {}).get("torque_Nm")
    torque = arr[:, tcol] if tcol is not None else np.full(arr.shape[0], float(stated or 0.0))
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
    _check_turn(str(p), head[ang], arr[:, ang], deg)
    if sing.mean() > MAX_SINGULAR_SHARE:
        where = ", ".join(f"{a:g}-{b:g}" for a, b in singular_ranges(deg, sing))
        raise InputError(f"reaction CSV {str(p)!r}: {int(sing.sum())} of {sing.size} rows are marked singular "
                         f"({100 * sing.mean():.3g} %, at most {100 * MAX_SINGULAR_SHARE:g} %): the reactions are "
                         f"unknown over crank {plain(where, 80)} deg, too few rows left to find their peaks")
    _check_forces(str(p), deg, {n: j.force_N for n, j in joints.items()}, sing)
    assumed = []
    if tcol is None and stated is None:
        raise InputError(f"reaction CSV {str(p)!r}: no driver-torque column (one of "
                         f"{', '.join(_TORQUE_COLS + ('driver_force_N',))}): the crank's load is unknown; add it, or "
                         f"state its value in the scene, e.g. [check] reactions_csv_missing = {{torque_Nm = 0}}")
    if tcol is None:
        assumed.append(f"the reaction CSV {p.name} has no driver-torque column: the torque is taken as "
                       f"{float(stated):g} N·m at every crank angle ([check].reactions_csv_missing)")
    absent = [n for n in linkage_joints or () if n not in joints]
    if absent:  # the scene's linkage needs a force at every joint
        raise InputError(f"reactions CSV {p.name} lacks joint(s) {', '.join(absent)}; "
                         f"the linkage has {', '.join(linkage_joints)}")
    for j in joints.values():
        j.force_N = np.where(np.isfinite(j.force_N), j.force_N, 0.0)        # blank singular rows
    meta = {"source": str(p), "model": "imported", "assumed": assumed}
    if "driver_force_N" in head:
        meta["driver_unit"] = "N"
    h = ReactionHistory(deg, joints, np.where(np.isfinite(torque), torque, 0.0), None, meta,
                        singular_mask=sing if sing.any() else None, full_turn=is_full_turn(deg))
    h.meta["singular"] = singular_ranges(deg, h.singular_mask)
    return h
