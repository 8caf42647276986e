"""``rigfem kinematics``: how a linkage moves — link angles and rates, point paths, velocities
and accelerations, transmission angle, mechanical advantage; over a turn the Grashof class,
dead points, toggles, limit positions and time ratio; curves (--plot) and a GIF (--animate).

Crank angles in degrees counter-clockwise from the ground line; rates in rad/s, rad/s²;
points in mm, mm/s, mm/s².  Closed form for the four-bar and slider-crank, the general
planar solver for the others.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from pathlib import Path

import lazy_loader

from rigfem import linkage, rig  # lazy (lazy_loader): numpy and the solvers load when a linkage moves
from rigfem.cli.exitcodes import RULES_SHOWN
from rigfem.cli.linkage_args import add_linkage_arguments, lengths
from rigfem.cli.outputs import new_output, write_file, wrote
from rigfem.errors import InputError, check_range
from rigfem.settings import REFERENCE_SCENE

np = lazy_loader.load("numpy")

HELP = "motion of a linkage: angles, velocities, accelerations, transmission angle, dead points, pictures"
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = f"motion printed; {RULES_SHOWN}"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_linkage_arguments(p)
    p.add_argument("--branch", metavar="open|crossed", help="four-bar assembly branch (default open)")
    p.add_argument("--coupler-point", nargs=2, metavar=("DIST", "ANGLE"),
                   help="four-bar coupler point: distance from A (mm), angle from the coupler line (deg)")
    p.add_argument("--omega", metavar="RAD_S", help="crank angular velocity (rad/s, negative = clockwise; "
                                                    "default the scene's, else 2π = 1 Hz)")
    p.add_argument("--alpha", metavar="RAD_S2", help="crank angular acceleration (rad/s², default 0 or the scene's)")
    p.add_argument("--at", nargs="+", metavar="DEG", help="crank angles (deg); default the scene's instant, else a turn")
    p.add_argument("--samples", metavar="N", help="crank angles over a turn (default 360)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    p.add_argument("--csv", metavar="PATH", help="write one row per crank angle")
    p.add_argument("--plot", metavar="PATH.png", help="angle, velocity, acceleration and transmission-angle curves")
    p.add_argument("--animate", metavar="PATH.gif", help="GIF of the linkage over one turn")
    p.add_argument("--force", action="store_true", help="replace existing --csv/--plot/--animate files (only files rigfem wrote)")


def _build(args):
    """(linkage, name, omega rad/s, alpha rad/s², instant deg or None, textbook)."""
    if args.scene and (args.four_bar or args.slider_crank):
        raise InputError("give either a scene or --four-bar/--slider-crank, not both")
    if args.offset is not None and not args.slider_crank:
        raise InputError("--offset applies only with --slider-crank")
    if (args.branch or args.coupler_point) and not args.four_bar:
        raise InputError("--branch and --coupler-point apply only with --four-bar (a scene gives its own)")
    omega, alpha, instant, textbook = 2 * math.pi, 0.0, None, False
    if args.four_bar:
        L = lengths(("B2", "B3", "B4", "D"), args.four_bar)
        cp = None
        if args.coupler_point:
            cp = (check_range("--coupler-point DIST", args.coupler_point[0], 0.0, 1e5, "mm"),
                  check_range("--coupler-point ANGLE", args.coupler_point[1], -360.0, 360.0, "deg"))
        lk = linkage.four_bar(*L, masses=None, branch=args.branch or "open", coupler_point=cp, whole_turn=False)
        name = "four-bar " + " ".join(args.four_bar)
    elif args.slider_crank:
        L = lengths(("B2", "B3"), args.slider_crank)
        off = 0.0 if args.offset is None else check_range("--offset", args.offset, -10000, 10000, "mm")
        lk = linkage.slider_crank(*L, off, masses=None, whole_turn=False)
        name = "slider-crank " + " ".join(args.slider_crank)
    else:
        from rigfem.scene import load_scene

        sc = load_scene(args.scene or REFERENCE_SCENE)
        lk, name = linkage.build(sc, whole_turn=False), sc.name
        omega, alpha, instant, textbook = 2 * math.pi * sc.speed_hz, sc.alpha_rad_s2, sc.instant_deg, sc.textbook
    if args.omega is not None:
        omega = check_range("--omega", args.omega, -1e4, 1e4, "rad/s")
        if omega == 0:
            raise InputError("--omega must be non-zero (rad/s)")
    if args.alpha is not None:
        alpha = check_range("--alpha", args.alpha, -1e7, 1e7, "rad/s²")
    return lk, name, omega, alpha, instant, textbook


def _refuse_existing(args) -> tuple:
    return tuple(new_output(flag, path, suffix, args.force) for flag, path, suffix in
                 (("--csv", args.csv, ".csv"), ("--plot", args.plot, ".png"), ("--animate", args.animate, ".gif")))


def _range_of_motion(name: str, turn: dict, samples: int) -> np.ndarray:
    """``samples`` crank angles over the arc a linkage that does not make a whole turn moves through
    (strictly between its dead points, the limit positions); InputError if it has no such arc."""
    if not turn.get("crank_range_deg"):
        raise InputError(f"{name}: the linkage does not assemble at any crank angle (dead points "
                         f"{', '.join(f'{x:.4f}' for x in turn['dead_points_deg'])} deg)")
    a, b = turn["crank_range_deg"]
    return np.linspace(a, b, samples + 2)[1:-1]   # the dead points themselves: rates unbounded


def _assembles(name: str, turn: dict, deg: float) -> float:
    """``deg`` moved into the crank's range of motion (by whole turns); InputError naming the
    range and the limit positions where the linkage does not assemble at ``deg``."""
    rng = turn.get("crank_range_deg")
    for a, b in turn.get("crank_ranges_deg") or ([rng] if rng else []):
        shifted = a + (deg - a) % 360.0
        if shifted <= b + 1e-9:
            return float(shifted if not a <= deg <= b else deg)
    dead = ", ".join(f"{x:.4f}" for x in turn["dead_points_deg"])
    arcs = turn.get("crank_ranges_deg") or ([rng] if rng else [])
    where = ("its crank moves only between " + " or between ".join(f"{a:.4f} and {b:.4f} deg" for a, b in arcs)
             if arcs else "it assembles nowhere")
    raise InputError(f"--at = {deg:g} deg: {name} does not assemble there ({where}; limit positions at "
                     f"the dead points {dead} deg)")


#: crank angles moved and written at a time: a turn of a million angles streams through memory
#: that of one chunk (no Python object per angle)
CHUNK = 16_384


class _Null:
    """Written as JSON's null by ``%r`` (a value that is unbounded exactly at a toggle)."""

    def __repr__(self) -> str:
        return "null"


_NULL = _Null()


def _columns(m: linkage.Motion) -> tuple[list[np.ndarray], str]:
    """Every per-angle value of ``m`` as a column, and the JSON text of one angle's record with a
    ``%r`` where each column's value goes (same keys and nesting as the whole result's)."""
    cols: list[np.ndarray] = [m.crank_deg]
    parts = ['"crank_deg": %r']

    def obj(items) -> str:
        return "{" + ", ".join(f"{json.dumps(k)}: {v}" for k, v in items) + "}"

    def num(a) -> str:
        cols.append(np.asarray(a, float))
        return "%r"

    parts.append('"links": ' + obj((n, obj((k, num(v[k])) for k in v)) for n, v in m.links.items()))
    parts.append('"points": ' + obj((n, obj((k, f"[{num(v[k][:, 0])}, {num(v[k][:, 1])}]") for k in v))
                                    for n, v in m.points.items()))
    if m.slider is not None:
        parts.append('"slider": ' + obj((k, num(v)) for k, v in m.slider.items()))
    if m.transmission_deg is not None:
        parts.append(f'"transmission_angle_deg": {num(m.transmission_deg)}')
        parts.append(f'"mechanical_advantage": {num(m.mechanical_advantage)}')
    return cols, "{" + ", ".join(parts) + "}"


def records_text(m: linkage.Motion, sep: str = ",\n  ") -> str:
    """The JSON records of every angle of ``m``, one a line, joined by ``sep`` (floats as JSON
    writes them, a non-finite value as null)."""
    cols, row = _columns(m)
    table = np.column_stack(cols) if m.crank_deg.size else np.zeros((0, len(cols)))
    values = table.ravel().tolist()
    for i in np.flatnonzero(~np.isfinite(table.ravel())):
        values[i] = _NULL
    return sep.join([row] * m.crank_deg.size) % tuple(values)


def _records(m: linkage.Motion) -> list[dict]:
    return json.loads("[" + records_text(m, ",") + "]")


def result(lk, name: str, textbook: bool, m: linkage.Motion, turn: dict | None,
           mu: tuple[float, float] | None) -> dict:
    """The JSON object but its angles: the linkage, its turn analysis and the transmission
    angle's range over the turn ``mu`` (min, max deg; None if it has none); ``m`` is (a chunk
    of) the motion, for its driver and definitions."""
    res = {"scene": name, "linkage": lk.meta.get("type"), "lengths_mm": lk.meta.get("lengths_mm"),
           "textbook": textbook, "branch": lk.meta.get("branch", m.meta.get("branch")),
           "method": "closed form" if m.meta.get("type") in ("four-bar", "slider-crank") else "general solver",
           "omega_rad_s": m.omega_rad_s, "alpha_rad_s2": m.alpha_rad_s2, "turn": turn}
    if mu is not None:
        res["transmission_angle_deg"] = {"min": mu[0], "max": mu[1], "rig_band": list(rig.MU_LIMITS_DEG),
                                         "within_band": bool(mu[0] > rig.MU_LIMITS_DEG[0] and mu[1] < rig.MU_LIMITS_DEG[1])}
    for k in ("mechanical_advantage", "transmission_angle"):
        if k in m.meta:
            res[f"{k}_definition"] = m.meta[k]
    res["rule_violations"] = [] if textbook else rig.broken_rules(lk.meta)
    return res


def write_json(res: dict, motions, out) -> None:
    """Write ``res`` with ``"angles"``: the records of every motion chunk of ``motions``, each
    written as it comes (the result is never held whole)."""
    head = json.dumps(res, indent=1)
    out.write(head[: head.rindex("}")].rstrip() + ',\n "angles": [')
    sep = "\n  "
    for m in motions:
        if m.crank_deg.size:
            out.write(sep + records_text(m))
            sep = ",\n  "
    out.write("\n ]\n}\n")


def _fmt(x, w=11, p=4) -> str:
    return f"{'unbounded':>{w}s}" if x is None else f"{x:{w}.{p}f}"


def format_table(res: dict, max_rows: int = 24, of: int | None = None) -> str:
    """Readable summary and a table of the motion (at most ``max_rows`` evenly chosen angles;
    ``of``: how many angles ``res["angles"]`` was chosen from, if not all)."""
    L = res["lengths_mm"] or {}
    out = [f"WARNING: breaks rig rule {v}" for v in res["rule_violations"]]   # first, whatever follows
    out += [f"{res['scene']}: {res['linkage']}  " + "  ".join(f"{k}={v:g}" for k, v in L.items()) + " mm"
           + (f"  branch={res['branch']}" if res.get("branch") else "")
           + f"   crank omega={res['omega_rad_s']:g} rad/s alpha={res['alpha_rad_s2']:g} rad/s²  ({res['method']})"]
    if res["textbook"]:
        out.append("textbook linkage (not a rig configuration): the rig's mounting rules do not apply")
    t = res["turn"]
    if t is None:
        out.append("turn analysis (dead points, limit positions, time ratio): closed form for the four-bar and "
                   "slider-crank only")
    else:
        if "grashof" in t:
            out.append(f"Grashof class: {t['grashof']}; crank turns fully: {'yes' if t['crank_turns_fully'] else 'no'}")
            for tg in t["toggles"]:
                out.append(f"toggle ({tg['kind']}, crank and coupler collinear): crank {tg['crank_deg']:.4f} deg, "
                           f"rocker at its limit {tg['rocker_deg']:.4f} deg")
            if t["rocker_swing_deg"] is not None:
                out.append(f"rocker swing {t['rocker_swing_deg']:.4f} deg between {t['rocker_limits_deg'][0]:.4f} and "
                           f"{t['rocker_limits_deg'][1]:.4f} deg")
        else:
            for lim in t["limits"]:
                out.append(f"{lim['kind']}: crank {lim['crank_deg']:.4f} deg, slider at {lim['slider_mm']:.4f} mm")
            if t["stroke_mm"] is not None:
                out.append(f"slider stroke {t['stroke_mm']:.4f} mm")
        change = t.get("change_points_deg") or []
        dead = [a for a in t["dead_points_deg"] if not any(abs((a - c + 180) % 360 - 180) < 1e-6 for c in change)]
        if change:
            out.append("change points (every link in line; the crank passes, the linkage may leave on either branch, "
                       "this follows the smooth one): " + ", ".join(f"{a:.4f}" for a in change) + " deg"
                       + ("; it comes back to its start after two turns" if t.get("turns_to_repeat") == 2 else ""))
        if dead:
            out.append("dead points (the crank cannot drive past): " + ", ".join(f"{a:.4f}" for a in dead)
                       + " deg" + (f"; crank range {t['crank_range_deg'][0]:.4f} to {t['crank_range_deg'][1]:.4f} deg"
                                   if t.get("crank_range_deg") else ""))
        if t["time_ratio"] is not None:
            a, b = t["stroke_crank_deg"]
            out.append(f"time ratio {t['time_ratio']:.4f} (strokes over {a:.4f} and {b:.4f} deg of crank)")
    mu = res.get("transmission_angle_deg")
    if mu:
        out.append(f"transmission angle over the turn: min {mu['min']:.4f} deg, max {mu['max']:.4f} deg "
                   f"({'inside' if mu['within_band'] else 'OUTSIDE'} the rig's {mu['rig_band'][0]:g}–{mu['rig_band'][1]:g} deg band)")
    if "mechanical_advantage_definition" in res:
        out.append(f"mechanical advantage = {res['mechanical_advantage_definition']}")
    rows = res["angles"]
    total = of or len(rows)
    if total > max_rows:
        out.append(f"\n(every {math.ceil(total / max_rows)}th of {total} angles; --json or --csv for all)")
        rows = rows[::math.ceil(len(rows) / max_rows)]
    links = [n for n in rows[0]["links"] if n != "crank"]
    head = f"{'crank deg':>9s}"
    for n in links:
        head += f" {n[:7] + ' deg':>11s} {'w rad/s':>11s} {'a rad/s²':>11s}"
    has_mu = "transmission_angle_deg" in rows[0]
    if "slider" in rows[0]:
        head += f" {'slider mm':>11s} {'v mm/s':>11s} {'a mm/s²':>11s}"
    if has_mu:
        head += f" {'mu deg':>8s} {'MA':>10s}"
    out += ["", head]
    for r in rows:
        line = f"{r['crank_deg']:9.3f}"
        for n in links:
            v = r["links"][n]
            line += f" {_fmt(v['angle_deg'], 11, 3)} {_fmt(v['omega_rad_s'])} {_fmt(v['alpha_rad_s2'])}"
        if "slider" in r:
            s = r["slider"]
            line += f" {_fmt(s['position_mm'], 11, 3)} {_fmt(s['velocity_mm_s'], 11, 3)} {_fmt(s['acceleration_mm_s2'], 11, 1)}"
        if has_mu:
            line += f" {_fmt(r['transmission_angle_deg'], 8, 3)} {_fmt(r['mechanical_advantage'], 10, 4)}"
        out.append(line)
    return "\n".join(out)


def _csv_columns(m: linkage.Motion) -> dict[str, np.ndarray]:
    cols = {"crank_deg": m.crank_deg}
    for n, v in m.links.items():
        for k, a in v.items():
            cols[f"{n}_{k}"] = a
    for n, v in m.points.items():
        for k, a in v.items():
            q, unit = k.split("_", 1)
            cols[f"{n}_x_{q}_{unit}"], cols[f"{n}_y_{q}_{unit}"] = a[:, 0], a[:, 1]
    if m.slider is not None:
        for k, a in m.slider.items():
            cols[f"slider_{k}"] = a
    if m.transmission_deg is not None:
        cols["transmission_angle_deg"] = m.transmission_deg
        cols["mechanical_advantage"] = m.mechanical_advantage
    return cols


def write_csv(motions, path: str | Path) -> None:
    """One row per crank angle: link angles and rates, point positions, velocities, accelerations
    (10 significant digits; an unbounded value empty).  ``motions``: a Motion or its chunks,
    each written as it comes."""
    chunks = [motions] if isinstance(motions, linkage.Motion) else motions
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        for i, m in enumerate(chunks):
            cols = _csv_columns(m)
            if i == 0:
                w.writerow(cols)
            table = np.column_stack(list(cols.values()))
            finite = np.isfinite(table).all(1)
            row = ",".join(["%.10g"] * table.shape[1]) + "\r\n"
            for a, b in _runs(finite):
                if finite[a]:
                    fh.write((row * (b - a)) % tuple(table[a:b].ravel().tolist()))
                else:
                    w.writerows(["" if not np.isfinite(x) else f"{x:.10g}" for x in r] for r in table[a:b])


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) of each run of equal values of ``mask``."""
    cut = np.flatnonzero(np.diff(mask.astype(np.int8))) + 1
    edges = np.concatenate([[0], cut, [mask.size]])
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def _chunks(lk, deg: np.ndarray, omega: float, alpha: float):
    """The motion at ``deg``, :data:`CHUNK` angles at a time."""
    for i in range(0, max(deg.size, 1), CHUNK):
        yield linkage.linkage_motion(lk, deg[i:i + CHUNK], omega, alpha)


def _mu_range(lk, deg: np.ndarray, omega: float, alpha: float) -> tuple[float, float] | None:
    """The transmission angle's least and greatest value at ``deg`` (None if it has none)."""
    lo, hi = math.inf, -math.inf
    for m in _chunks(lk, deg, omega, alpha):
        if m.transmission_deg is None:
            return None
        lo, hi = min(lo, float(m.transmission_deg.min())), max(hi, float(m.transmission_deg.max()))
    return lo, hi


def run(args) -> int:
    csv_path, png, gif = _refuse_existing(args)
    lk, name, omega, alpha, instant, textbook = _build(args)
    samples = 360
    if args.samples is not None:
        samples = check_range("--samples", args.samples, 8, 1_000_000)
        if samples != int(samples):
            raise InputError(f"--samples = {args.samples!r} must be a whole number in [8, 1000000]")
    samples = int(samples)
    turn = linkage.linkage_turn(lk)
    full = linkage.crank_angles(samples)
    if turn is not None and not turn["crank_turns_fully"]:
        full = _range_of_motion(name, turn, samples)
    if args.at:
        deg = np.array([check_range("--at", v, -3600.0, 3600.0, "deg") for v in args.at])
        if turn is not None and not turn["crank_turns_fully"]:
            deg = np.array([_assembles(name, turn, a) for a in deg])
    elif instant is not None and args.samples is None:
        deg = np.array([instant])
    else:
        deg = full
    first = linkage.linkage_motion(lk, deg[:1], omega, alpha)   # the driver and definitions
    mu = _mu_range(lk, full, omega, alpha) if (turn is not None or deg is full) else None
    res = result(lk, name, textbook, first, turn, mu)
    title = f"{name}: {lk.meta.get('type')} " + ", ".join(f"{k} {v:g}" for k, v in (lk.meta.get("lengths_mm") or {}).items()) + " mm"
    if csv_path:
        write_file(csv_path, lambda tmp: write_csv(_chunks(lk, deg, omega, alpha), tmp))
    if png:
        from rigfem.report.motion import motion_plot

        write_file(png, lambda tmp: motion_plot(linkage.linkage_motion(lk, full, omega, alpha), tmp, title))
    if gif:
        from rigfem.report.motion import motion_gif

        marks = []
        if turn is not None:
            marks = [t["crank_deg"] for t in turn.get("toggles", [])] + [t["crank_deg"] for t in turn.get("limits", [])]
        write_file(gif, lambda tmp: motion_gif(linkage.linkage_motion(lk, linkage.crank_angles(72), omega, alpha), tmp, title, marks))
    if args.json:
        write_json(res, _chunks(lk, deg, omega, alpha), sys.stdout)
    else:
        shown = deg[::math.ceil(deg.size / 24)]
        res["angles"] = _records(linkage.linkage_motion(lk, shown, omega, alpha))
        print(format_table(res, of=deg.size))
    wrote(csv_path, png, gif)
    return 0
