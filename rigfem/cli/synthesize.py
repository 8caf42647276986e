"""``rigfem synthesize function|motion``: a four-bar that generates y = f(x) (Freudenstein's
equation, Chebyshev precision points) or moves a coupler point through three positions, its
errors and defects; ``--rig`` then ranks the nearest buildable rig configurations, each with
its rule table and stress verdict (``rigfem.design.rig_design``).

Angles in degrees counter-clockwise from the ground line O2→O4; lengths in the unit of
--ground (function) or of the positions (motion); rig lengths in mm.  Exit status with
--rig and the stress check: 0 if a listed configuration passes every part, 1 if none does.
"""

from __future__ import annotations

import argparse
import json
import re

from rigfem.cli.outputs import new_output, write_file, write_text, wrote
from rigfem.cli.progress import OBSERVER
from rigfem.errors import ComputeError, InputError, check_range
from rigfem.settings import FIDELITY

HELP = ("design a linkage: a four-bar generating a function or a coupler-point motion, and with --rig "
        "the nearest buildable rig configurations, checked")
#: the meaning of exit codes 0 and 1
SUCCESS = ("linkage found (with --rig and stress: a listed configuration passes), 1 no listed configuration "
           "passes or the generated function is far beyond useful accuracy")


def _rig_arguments(p: argparse.ArgumentParser, motion: bool) -> None:
    g = p.add_argument_group("snap to the rig")
    g.add_argument("--rig", action="store_true",
                   help="rank the rig four-bars that meet the rig rules (60 mm grid, every rule) that do the job best, "
                        "each with its rule table and stress verdict")
    g.add_argument("--top", metavar="N", help="rig configurations listed (default 5, 1-50)")
    g.add_argument("--fidelity", help="FE preset of the stress verdicts: draft (default), standard, fine")
    g.add_argument("--no-stress", action="store_true", help="rules and motion error only (no FE)")
    g.add_argument("--scene-out", metavar="TOML", help="write the best rig configuration as a scene file "
                                                        "(then: rigfem check TOML)")
    p.add_argument("--force", action="store_true",
                   help="replace existing --plot/--scene-out files (only files rigfem wrote)")
    if motion:
        g.add_argument("--scale", metavar="K", help="rig mm per unit of the positions (default: every scale "
                                                    "at which the design fits the rails)")


def add_arguments(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="task", metavar="TASK", parser_class=type(p))
    f = sub.add_parser("function", help="function generation y = f(x) with a four-bar",
                       description="function generation y = f(x) with a four-bar")
    f.add_argument("expr", metavar="EXPR", help="f(x), e.g. 'x*log(x)' (x, numbers, + - * / **, pi, e, numpy sin cos "
                                                "tan exp log log10 sqrt ...)")
    f.add_argument("--x", nargs=2, required=True, metavar=("X0", "X1"), help="range of x")
    f.add_argument("--input", nargs=2, required=True, metavar=("START", "RANGE"),
                   help="crank angle at X0 and its sweep (deg)")
    f.add_argument("--output", nargs=2, required=True, metavar=("START", "RANGE"),
                   help="rocker angle at f(X0) and its sweep (deg)")
    f.add_argument("--ground", required=True, metavar="D", help="ground length d (sets the unit of a, b, c)")
    f.add_argument("--points", default="3", metavar="N", help="precision points (3)")
    f.add_argument("--json", action="store_true", help="print one JSON object")
    f.add_argument("--plot", metavar="PNG", help="plot of the structural error over the range")
    _rig_arguments(f, motion=False)
    m = sub.add_parser("motion", help="three-position motion generation of a coupler point",
                       description="three-position motion generation of a coupler point (dyads in standard "
                                   "form); without the crank and rocker rotations the free choices maximise the smallest "
                                   "transmission angle")
    # "-15.12,-9" is a position, not an option: let argparse read negative coordinates
    m._negative_number_matcher = re.compile(r"^-\.?\d")
    m.add_argument("--points", nargs=3, required=True, metavar="X,Y", help="the three positions, in order")
    m.add_argument("--coupler-rotations", "--alpha", dest="alpha", nargs=2, metavar=("A2", "A3"),
                   help="coupler rotations from position 1 to 2 and 3 (deg; alias --alpha)")
    m.add_argument("--crank-rotations", "--beta", dest="beta", nargs=2, metavar=("B2", "B3"),
                   help="crank rotations from position 1 to 2 and 3 (deg; alias --beta)")
    m.add_argument("--rocker-rotations", "--gamma", dest="gamma", nargs=2, metavar=("G2", "G3"),
                   help="rocker rotations from position 1 to 2 and 3 (deg; alias --gamma)")
    m.add_argument("--json", action="store_true", help="print one JSON object")
    _rig_arguments(m, motion=True)


def _table(r: dict) -> str:
    L = r["lengths"]
    out = [f"four-bar generating y = {r['expression']} for x in [{r['x_range'][0]:g}, {r['x_range'][1]:g}]",
           f"input (crank) {r['input_deg']['start']:g} deg over {r['input_deg']['range']:g} deg, output (rocker) "
           f"{r['output_deg']['start']:g} deg over {r['output_deg']['range']:g} deg",
           "",
           f"links: input a = {L['a']:.6g}, coupler b = {L['b']:.6g}, output c = {L['c']:.6g}, "
           f"ground d = {L['d']:.6g}"]
    if r["input_offset_deg"] or r["output_offset_deg"]:
        out.append(f"(Freudenstein gave negative lengths: crank drawn at input + {r['input_offset_deg']:g} deg, "
                   f"rocker at output + {r['output_offset_deg']:g} deg)")
    out.append(f"assembly branch: {r['branch'] or 'none'}")
    out.append("")
    out.append(f"{'precision point':>16s} {'x':>10s} {'y':>10s} {'input deg':>10s} {'output deg':>11s}")
    for i, p in enumerate(r["precision_points"], 1):
        out.append(f"{i:16d} {p['x']:10.5f} {p['y']:10.5f} {p['input_deg']:10.4f} {p['output_deg']:11.4f}")
    if "structural_error" in r:
        s = r["structural_error"]
        out.append(f"\nstructural error: max |generated - ideal| = {s['max_abs']:.5g} at x = {s['at_x']:.4g} "
                   f"({s['percent_of_range']:.3f} % of the output range)")
        t = r["transmission_deg"]
        out.append(f"transmission angle over the range: min {t['min']:.2f} deg, max {t['max']:.2f} deg")
    for d in r["defects"]:
        out.append(f"DEFECT: {d}")
    if not r["defects"]:
        out.append("no branch or order defect")
    return "\n".join(out)


#: largest coordinate or length accepted (in the unit of the positions or of --ground)
MAX_COORD = 1e9


def _point(text: str) -> tuple[float, float]:
    parts = text.split(",")
    if len(parts) != 2:
        raise InputError(f"--points: {text!r} must be X,Y")
    return (check_range("--points X", parts[0], -MAX_COORD, MAX_COORD),
            check_range("--points Y", parts[1], -MAX_COORD, MAX_COORD))


def _distinct(P: list[tuple[float, float]]) -> None:
    """Three positions, no two coincident (to 1e-9 of their span): else InputError naming them."""
    span = max(max(abs(a - b) for a, b in zip(p, q)) for p in P for q in P)
    for i in range(3):
        for j in range(i + 1, 3):
            if max(abs(a - b) for a, b in zip(P[i], P[j])) <= 1e-9 * max(span, 1e-300):
                raise InputError(f"--points: position {i + 1} = {P[i][0]:g},{P[i][1]:g} and position {j + 1} = "
                                 f"{P[j][0]:g},{P[j][1]:g} coincide; give three distinct positions")


def _motion(args) -> int:
    from rigfem.linkage.synthesis import (
        check_three_position,
        optimise_three_position,
        three_position,
    )

    P = [_point(t) for t in args.points]
    _distinct(P)
    rig = _rig_options(args, motion=True)

    def angles(flag, v):
        return None if v is None else [check_range(flag, a, -360, 360, "deg") for a in v]

    al, be, ga = (angles("--coupler-rotations", args.alpha), angles("--crank-rotations", args.beta),
                  angles("--rocker-rotations", args.gamma))
    if (be is None) != (ga is None) or (be is not None and al is None):
        raise InputError("give --coupler-rotations, --crank-rotations and --rocker-rotations together "
                         "(analytic), or none/only --coupler-rotations (optimised)")
    r = three_position(P, al, be, ga) if be is not None else optimise_three_position(P, al)
    r["optimised"] = be is None
    r.update(check_three_position(r))
    status = _snap(r, rig, "motion") if rig else 0
    if args.json:
        print(json.dumps(r, indent=1))
        wrote(rig and rig["scene"])
        return status
    L = r["lengths"]
    how = "optimised free choices (largest smallest transmission angle)" if r["optimised"] else "given free choices"
    out = [how + f": coupler rotations {r['alpha_deg'][0]:.3f}, {r['alpha_deg'][1]:.3f} deg; crank {r['beta_deg'][0]:.3f}, "
           f"{r['beta_deg'][1]:.3f} deg; rocker {r['gamma_deg'][0]:.3f}, {r['gamma_deg'][1]:.3f} deg",
           f"ground pivots O2 = ({r['O2'][0]:.4f}, {r['O2'][1]:.4f}), O4 = ({r['O4'][0]:.4f}, {r['O4'][1]:.4f})",
           f"links: crank {L['b2']:.4f}, coupler {L['b3']:.4f}, rocker {L['b4']:.4f}, ground {L['d']:.4f}; "
           f"coupler point {r['coupler_point']['distance']:.4f} from A at {r['coupler_point']['angle_deg']:.3f} deg "
           f"from A->B",
           "crank angles at the positions (deg, from O2->O4): " + ", ".join(f"{c:.3f}" for c in r["crank_deg"]),
           f"branch {r['branch']}; {r.get('grashof', '')}"]
    if r.get("transmission_deg"):
        out.append(f"transmission angle over a turn: min {r['transmission_deg']['min']:.2f} deg, "
                   f"max {r['transmission_deg']['max']:.2f} deg")
    if "position_error" in r:
        out.append(f"positions reproduced by the kinematics to {r['position_error']:.2e}")
    out += [f"DEFECT: {d}" for d in r["defects"]] or ["no branch or order defect"]
    print("\n".join(out))
    if rig:
        print(_rig_text(r["rig"], "motion"))
    wrote(rig and rig["scene"])
    return status


def run(args) -> int:
    if getattr(args, "task", None) == "motion":
        return _motion(args)
    if getattr(args, "task", None) != "function":
        raise InputError("give a task: rigfem synthesize function EXPR --x X0 X1 --input START RANGE "
                         "--output START RANGE --ground D, or rigfem synthesize motion --points X,Y X,Y X,Y")
    from rigfem.linkage.synthesis import synthesize_function

    png = new_output("--plot", args.plot, ".png", args.force)
    rig = _rig_options(args, motion=False)
    nums = dict(x0=check_range("--x X0", args.x[0], -1e15, 1e15), x1=check_range("--x X1", args.x[1], -1e15, 1e15),
                in_start=check_range("--input START", args.input[0], -360, 360, "deg"),
                in_range=check_range("--input RANGE", args.input[1], -360, 360, "deg"),
                out_start=check_range("--output START", args.output[0], -360, 360, "deg"),
                out_range=check_range("--output RANGE", args.output[1], -360, 360, "deg"),
                d=check_range("--ground", args.ground, 0, MAX_COORD, lo_open=True))
    points = check_range("--points", args.points, 3, 3)
    r = synthesize_function(args.expr, points=int(points), **nums)
    gen = r.pop("generated", None)
    if png and gen is not None:
        from rigfem.report.motion import structural_error_plot

        write_file(png, lambda tmp: structural_error_plot(gen, r, tmp))
    status = _snap(r, rig, "function") if rig else 0
    if any(d.startswith("accuracy defect") for d in r["defects"]):
        status = max(status, 1)   # flagged: this linkage does not generate the function
    if args.json:
        print(json.dumps(r, indent=1))
    else:
        print(_table(r))
        if rig:
            print(_rig_text(r["rig"], "function"))
    wrote(png if gen is not None else None, rig and rig["scene"])
    return status


def _rig_options(args, motion: bool) -> dict | None:
    """The --rig options, checked before anything is computed."""
    scale = args.scale if motion else None
    given = [f for f, v in (("--top", args.top), ("--fidelity", args.fidelity), ("--no-stress", args.no_stress),
                            ("--scene-out", args.scene_out), ("--scale", scale)) if v]
    if not args.rig:
        if given:
            raise InputError(f"{', '.join(given)} {'needs' if len(given) == 1 else 'need'} --rig")
        return None
    top = check_range("--top", args.top or 5, 1, 50)
    if top != int(top):
        raise InputError(f"--top = {args.top!r} must be a whole number in [1, 50]")
    fidelity = args.fidelity or "draft"
    if fidelity not in FIDELITY:
        raise InputError(f"--fidelity = {fidelity!r} must be one of {', '.join(FIDELITY)}")
    from rigfem.mesh.mesher import MACHINE_GIB
    from rigfem.sweep.cost import check_cost, synthesis_cost
    from rigfem.sweep.configs import SweepParams

    check_cost(synthesis_cost(SweepParams(fidelity=fidelity), int(top), not args.no_stress), MACHINE_GIB)
    return dict(top=int(top), fidelity=fidelity, stress=not args.no_stress,
                scale=None if scale is None else check_range("--scale", scale, 0.0, 1e4, lo_open=True),
                scene=new_output("--scene-out", args.scene_out, ".toml", args.force))


def _snap(r: dict, opts: dict, task: str) -> int:
    """Rank the rig configurations into ``r["rig"]``; write the scene; the exit status."""
    from rigfem.cache import from_environment
    from rigfem.context import Context
    from rigfem.design.rig_design import snap_function, snap_motion, stress_verdicts
    from rigfem.sweep.bases import mesh_ahead
    from rigfem.sweep.configs import SweepParams

    if r.get("branch") is None:
        raise ComputeError("the synthesised linkage has a branch defect: nothing to snap to the rig")
    ctx = Context(from_environment(), OBSERVER)
    if opts["stress"]:  # the unit solutions' meshes are made while the rig four-bars are ranked
        mesh_ahead(SweepParams(fidelity=opts["fidelity"]), ctx.cache)
    OBSERVER.stage("ranking the rig four-bars")
    cands = snap_function(r, opts["top"]) if task == "function" else snap_motion(r, opts["top"], opts["scale"])
    if opts["stress"]:
        stress_verdicts(cands, SweepParams(fidelity=opts["fidelity"]), ctx)
    r["rig"] = {"candidates": cands, "stress_fidelity": opts["fidelity"] if opts["stress"] else None}
    if opts["scene"] is not None:
        write_text(opts["scene"], _scene_toml(cands[0], task))
        r["rig"]["scene"] = str(opts["scene"])
    if not opts["stress"]:
        return 0
    return 0 if any(c["stress"]["verdict"] == "pass" for c in cands) else 1


def _scene_toml(c: dict, task: str) -> str:
    L = c["lengths_mm"]
    lines = [f"# The rig configuration rigfem synthesize {task} --rig ranked first "
             f"(error {c['error_pct']:.3g} % of the {'output range' if task == 'function' else 'positions span'}).",
             "[linkage]", 'type = "four-bar"',
             f'title = "Rig four-bar for {task} generation ({L["b2"]:g}/{L["b3"]:g}/{L["b4"]:g}/{L["d"]:g} mm)"',
             *(f"{k} = {v:.1f}" for k, v in L.items()), f'branch = "{c["branch"]}"', "speed_hz = 1.0",
             'masses = "rig"']
    if task == "motion":
        cp = c["coupler_point"]
        lines += ["", "[linkage.coupler_point]", f"distance_mm = {cp['distance_mm']:.3f}",
                  f"angle_deg = {(cp['angle_deg'] + 180.0) % 360.0 - 180.0:.4f}"]
    return "\n".join(lines) + "\n"


def _rig_text(rig: dict, task: str) -> str:
    """The ranked rig configurations: lengths, error, rule table, stress verdict."""
    out = ["", "nearest buildable rig configurations (60 mm hole grid, every rig rule), best first"
                + (f"; stress verdicts at {rig['stress_fidelity']} fidelity" if rig["stress_fidelity"] else "") + ":"]
    for i, c in enumerate(rig["candidates"], 1):
        L = c["lengths_mm"]
        head = f"\n{i}. b2 {L['b2']:g}, b3 {L['b3']:g}, b4 {L['b4']:g}, d {L['d']:g} mm, {c['branch']} branch: "
        if task == "function":
            head += (f"structural error {c['error']:.4g} ({c['error_pct']:.2f} % of the output range); crank at "
                     f"{c['input_start_deg']:.2f} deg and rocker at {c['output_start_deg']:.2f} deg at X0")
        else:
            cp = c["coupler_point"]
            head += (f"scale {c['scale']:.4g} mm per unit, motion error {c['error_mm']:.3g} mm "
                     f"({c['error_pct']:.3g} % of the positions' span); coupler point {cp['distance_mm']:.1f} mm from A "
                     f"at {cp['angle_deg']:.2f} deg from A->B"
                     + (f" (a marker arm {cp['off_rail_mm']:.0f} mm off the coupler rail)" if cp["off_rail_mm"] > 0.5
                        else " (on the coupler rail)")
                     + "; crank at " + ", ".join(f"{a:.1f}" for a in c["crank_deg"]) + " deg")
        out.append(head)
        for rule in c["rules"]:
            out.append(f"   {'ok  ' if rule['ok'] else 'FAIL'} {rule['name']}: {rule['value']:.4g} {rule['unit']}".rstrip())
        st = c.get("stress")
        if st is None:
            continue
        if "max_util_pct" in st:
            band = st["parts_band_pct"].get(st["limiting_part"].replace(" (", "_").rstrip(")"), 0.0)
            out.append(f"   stress: {st['verdict'].upper()}, worst {st['max_util_pct']:.1f} % of sigma_u/2 "
                       f"({st['limiting_part']}, error band ±{band:.1f} % of its peak)")
        else:
            out.append(f"   stress: {st['verdict'].upper()} ({st['note']})")
    if rig.get("scene"):
        out.append(f"\nbest configuration written to {rig['scene']}: rigfem check {rig['scene']}")
    return "\n".join(out)
