"""``rigfem reactions``: rig rules, transmission angle, peak pin reactions and torque of a linkage.

With no configuration it runs the reference scene, the same as ``rigfem check``'s.  Lengths in mm, forces N, torque N·m.
"""

from __future__ import annotations

import argparse
import json
import math

from rigfem.settings import MODELS, REFERENCE_SCENE
from rigfem.cli.exitcodes import RULES_SHOWN
from rigfem.cli.linkage_args import add_linkage_arguments, lengths
from rigfem.errors import InputError, check_range
from rigfem.cli.outputs import new_output, write_file, wrote

HELP = "peak pin reactions, driver torque and rig rules of a linkage over one crank turn"
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = f"table printed; {RULES_SHOWN}"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_linkage_arguments(p)
    p.add_argument("--speed-hz", metavar="HZ", help="crank speed (Hz, default 1 or the scene's)")
    p.add_argument("--model", default="rigid-body", metavar="MODEL",
                   help="mass model: rigid-body (default) or original (the 2013 program, four-bar only)")
    p.add_argument("--samples", default="360", metavar="N", help="crank angles per turn (default 360)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    p.add_argument("--csv", metavar="PATH", help="write the full history per crank angle")
    p.add_argument("--plot", metavar="PATH.png", help="plot reactions and torque against crank angle")
    p.add_argument("--force", action="store_true", help="replace existing --csv/--plot files (only files rigfem wrote)")


def _build(args) -> tuple[object, float, str]:
    from rigfem.dynamics.forces import loaded_linkage
    from rigfem.linkage.mechanisms import four_bar, slider_crank

    speed = None
    if args.speed_hz is not None:
        speed = check_range("--speed-hz", args.speed_hz, 0.0, 100.0, "Hz", lo_open=True)
    if args.offset is not None and not args.slider_crank:
        raise InputError("--offset applies only with --slider-crank")
    if args.scene and (args.four_bar or args.slider_crank):
        raise InputError("give either a scene or --four-bar/--slider-crank, not both")
    if args.four_bar:
        lk = four_bar(*lengths(("B2", "B3", "B4", "D"), args.four_bar))
    elif args.slider_crank:
        off = 0.0 if args.offset is None else check_range("--offset", args.offset, -10000, 10000, "mm")
        lk = slider_crank(*lengths(("B2", "B3"), args.slider_crank), off)
    else:
        from rigfem.scene import load_scene

        sc = load_scene(args.scene or REFERENCE_SCENE)
        lk, speed = loaded_linkage(sc), speed if speed is not None else sc.speed_hz
    return lk, (1.0 if speed is None else speed)


def massless_note(lk, scene: str) -> str | None:
    """The message for a linkage with no mass and no external load (every reaction is zero),
    pointing to ``rigfem kinematics``; None if it has masses or loads."""
    if lk.loads or any(b.totals()[0] > 0 for b in lk.bodies):
        return None
    return (f"{scene} has no masses and no external loads, so every pin reaction and the driver torque "
            f"are zero; for its motion (angles, velocities, accelerations, transmission angle) run "
            f"`rigfem kinematics {scene}`")


def format_table(res: dict) -> str:
    """Readable table of a result dict."""
    L = res["lengths_mm"] or {}
    out = [f"WARNING: breaks rig rule {v}" for v in res["rule_violations"]]   # first, whatever follows
    out.append(f"{res['linkage']}  " + "  ".join(f"{k}={v:g}" for k, v in L.items()) + " mm"
               f"   model={res['model']}  speed={res['speed_hz']:g} Hz  samples={res['samples']}")
    if res.get("textbook"):
        out.append("\ntextbook linkage (not a rig configuration): the rig's mounting rules do not apply")
    elif res["rules"]:
        out.append("")
        out.append(f"{'rule':58s} {'value':>10s} {'limit':>10s}  ok")
        for r in res["rules"]:
            out.append(f"{r['name']:58s} {r['value']:10.3f} {r['relation']:>2s}{r['limit']:8.3f}  "
                       f"{'yes' if r['ok'] else 'NO'}")
    mu = res["transmission_angle_deg"]
    if mu:
        out.append(f"\ntransmission angle: min {mu['min']:.4f} deg, max {mu['max']:.4f} deg")
    sing = res["singular"]
    sing_txt = ", ".join(f"{a:.1f}-{b:.1f} deg" for a, b in sing) if sing else ""
    out.append("")
    out.append(f"{'joint':10s} {'peak |F| (N)':>14s} {'at crank (deg)':>15s} {'Fx (N)':>12s} {'Fy (N)':>12s}")
    for name, pk in res["peaks"].items():
        if pk["singular"]:
            out.append(f"{name:10s} {'SINGULAR':>14s}  toggle near crank {sing_txt}: no finite peak")
        else:
            fx, fy = (round(v, 4) + 0.0 for v in (pk["fx_N"], pk["fy_N"]))     # no "-0.0000"
            out.append(f"{name:10s} {pk['force_N']:14.4f} {pk['crank_deg']:15.4f} {fx:12.4f} {fy:12.4f}")
    key = "torque_Nm" if "torque_Nm" in res else "driver_force_N"
    tq = res[key]
    label = "peak driver torque (N·m)" if key == "torque_Nm" else "peak driver force (N)"
    if tq["singular"]:
        out.append(f"{label}: SINGULAR (toggle near crank {sing_txt})")
    else:
        out.append(f"{label}: {tq['peak']:.4f} at crank {tq['crank_deg']:.4f} deg")
    if sing:
        out.append(f"\nWARNING: toggle (singular) configuration near crank {sing_txt}; "
                   "reactions grow without bound there")
    for w in res["warnings"]:
        out.append(f"WARNING: {w}")
    return "\n".join(out)


def run(args) -> int:
    from rigfem.dynamics.cycle import simulate
    from rigfem.dynamics.history import summary
    from rigfem.io.reactions_csv import write_csv
    from rigfem.rig.rules import broken_rules
    from rigfem.report.pictures import reactions_plot

    if args.model not in MODELS:
        raise InputError(f"--model = {args.model!r} must be one of {', '.join(MODELS)}")
    samples = check_range("--samples", args.samples, 8, 1_000_000)
    if samples != int(samples):
        raise InputError(f"--samples = {args.samples!r} must be a whole number in [8, 1000000]")
    csv_path = new_output("--csv", args.csv, ".csv", args.force)
    png = new_output("--plot", args.plot, ".png", args.force)
    lk, speed = _build(args)
    note = massless_note(lk, args.scene or ("this linkage" if args.four_bar or args.slider_crank else REFERENCE_SCENE))
    if note:
        print(json.dumps({"linkage": lk.meta.get("type"), "massless": True, "note": note}, indent=1)
              if args.json else note)
        return 0
    h = simulate(lk, samples=int(samples), speed_hz=speed, model=args.model)
    res = summary(h)
    res["rule_violations"] = broken_rules(h.meta)   # [] for a textbook linkage (not a rig configuration)
    if csv_path:
        write_file(csv_path, lambda tmp: write_csv(h, tmp))
    if png:
        write_file(png, lambda tmp: reactions_plot(h, tmp))
    if args.json:
        print(json.dumps(_finite(res), indent=1))
    else:
        print(format_table(res))
    wrote(csv_path, png)
    return 0


def _finite(obj):
    """Guard: no NaN/inf may reach output (JSON null instead)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj
