"""``rigfem check``: pass/fail stress verdict per part for a rig configuration (a scene).

Exit code 0 when every part passes, 1 when a part fails or cannot be decided, 2 on bad input.
"""

from __future__ import annotations

import argparse
import json
import os
import tomllib
from pathlib import Path

from rigfem.cli.exitcodes import EXIT
from rigfem.cli.linkage_args import add_rule_argument
from rigfem.cli.outputs import check_place, wrote
from rigfem.cli.progress import OBSERVER, above
from rigfem.errors import plain
from rigfem.settings import REFERENCE_SCENE

HELP = "stress verdict (σu/2) per part of a rig configuration, with report, VTK files and plots"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", nargs="?", default=REFERENCE_SCENE,
                   help=f"scene file (TOML) or built-in scene name (default {REFERENCE_SCENE})")
    p.add_argument("--list", action="store_true", help="list the built-in scenes and exit")
    p.add_argument("--out", metavar="DIR", help="result folder (default results/<scene>)")
    p.add_argument("--force", action="store_true",
                   help="replace an existing result folder (only one rigfem wrote: it holds .rigfem-result)")
    add_rule_argument(p)
    p.add_argument("--fidelity", help="draft | standard | fine (overrides the scene): each part is refined until "
                   "its verdict is decided and its band is within ±10 | ±3 | ±1 %% of the allowable; fine also "
                   "refines every part until its band is within ±5 %% of its own peak or it reaches the fine mesh")
    p.add_argument("--order", type=int, help="element order 1 | 2")
    p.add_argument("--size", type=float, metavar="MM", help="global mesh size (mm)")
    p.add_argument("--local-size", type=float, metavar="MM", help="mesh size at loaded interfaces (mm)")
    p.add_argument("--no-adaptive", dest="adaptive", action="store_false", default=None,
                   help="mesh every part at the preset (default: refine each part only until its verdict is decided)")
    p.add_argument("--modes", help="comma list: original,cycle")
    p.add_argument("--parts", help="comma list of parts to check (default: all of the linkage)")
    p.add_argument("--samples", type=int, help="crank angles per turn (default 360)")
    p.add_argument("--model", help="mass model: rigid-body (default) or original")
    p.add_argument("--frames", type=int, help="VTU frames of the cycle animation (default 12, 0 = none)")
    p.add_argument("--reactions-csv", metavar="PATH",
                   help="reaction history from outside (CSV as written by rigfem reactions --csv) "
                        "instead of rigfem's dynamics; the scene's linkage places the loads")
    p.add_argument("--solver", default="auto", help="auto | pardiso | superlu | amg")
    p.add_argument("--export-inp", action="store_true",
                   help="also write each part case at its critical crank angle as a CalculiX deck (.inp)")
    p.add_argument("--author", help="the report's author, in its title block (default: the scene's [report] author)")
    p.add_argument("--json", action="store_true", help="print the report JSON instead of the summary")
    p.add_argument("--quiet", action="store_true", help="no progress bar or progress lines")
    p.add_argument("--no-pictures", action="store_true",
                   help="skip the PNG pictures (scripted runs, CI); the report says they were not made")


def _list(text: str | None) -> list[str] | None:
    """A comma list option: None if not given; an empty one stays empty (the schema refuses it)."""
    return None if text is None else [x.strip() for x in text.split(",") if x.strip()]


def _overrides(a: argparse.Namespace) -> dict:
    o = {"fidelity": a.fidelity, "order": a.order, "size_mm": a.size, "local_size_mm": a.local_size,
         "adaptive": a.adaptive,
         "samples": a.samples, "mass_model": a.model, "frames": a.frames,
         "reactions_csv": str(Path(a.reactions_csv).resolve()) if a.reactions_csv else None,
         "modes": _list(a.modes), "parts": _list(a.parts)}
    return {k: v for k, v in o.items() if v is not None}


def _summary(r: dict) -> str:
    """The terminal's summary: the governing part case first, then every part case by utilisation
    (units in every header, numbers rounded to what they mean), then the verdict and its scope."""
    from rigfem.report.document import verdict_line
    from rigfem.report.figures import allowable_label, asked_text, band, by_utilisation, sf_text, stopped_text

    allowable = allowable_label(r["settings"]["limit_factor"], r["limit_mpa"])
    lines = [f"{plain(r['scene'])}: {plain(r['description'])}"]
    c = r.get("conclusion")
    if c:
        lo, hi = c["utilisation_band_pct"]
        lines.append(f"governing: {c['name']} ({c['part']}), {c['mode']} mode: {c['utilisation_pct']:.1f} % of the "
                     f"{allowable} (band {lo:.1f}-{hi:.1f} %"
                     + (f": ±{c['band_mpa']:.1f} MPa, ±{(hi - lo) / 2:.1f} % of the allowable, ±{c['error_pct']:.1f} % "
                        f"of the peak" if "band_mpa" in c else "")
                     + f"), factor of safety {sf_text(c['min_safety_factor'])}, "
                     f"reserve {c['reserve_pct']:.1f} %")
    lines.append(f"{'part':14s} {'mode':9s} {'peak σvm (MPa)':>14s} {'band (±MPa)':>11s} {'(±% allow.)':>11s} "
                 f"{'(±% peak)':>9s} {'util. (%)':>9s} {'FoS (–)':>7s} {'crank (deg)':>11s}  verdict    where  "
                 f"mesh stopped (why)")
    for p in by_utilisation(r["parts"]):
        if p.get("peak_mpa") is None:
            lines.append(f"{p['name']:14s} {p['mode']:9s} {'-':>14s} {'-':>11s} {'-':>11s} {'-':>9s} {'-':>9s} "
                         f"{'-':>7s} {'-':>11s}  "
                         f"{p['verdict'].upper():9s}  {p['notes'][0]}")
            continue
        why = f": {plain(p['reason'])}" if p.get("reason") else ""
        b = band(p)
        lines.append(f"{p['name']:14s} {p['mode']:9s} {p['peak_mpa']:14.1f} {b['mpa']:11.1f} "
                     f"{b['pct_of_allowable']:11.1f} {b['pct_of_peak']:9.1f} {p['utilisation_pct']:9.1f} "
                     f"{sf_text(p.get('safety_factor')):>7s} {p['crank_deg']:11.1f}  "
                     f"{p['verdict'].upper():9s}  {p['surface']}{why}  "
                     f"{(p.get('mesh') or {}).get('level', '–')} ({stopped_text(p)})")
    lines[0:0] = ([f"WARNING: breaks rig rule {plain(v)} (--allow-rule-violations)" for v in r["rule_violations"]]
                  + [f"ASSUMED: {plain(v)}" for v in r.get("assumed", [])])
    asked = dict.fromkeys(asked_text(p) for p in r["parts"] if p.get("peak_mpa") is not None)
    if asked:
        lines.append(f"mesh asked: {'; '.join(asked)}")
    if r.get("not_checked", {}).get("parts"):
        lines.append(f"not checked: {', '.join(r['not_checked']['parts'])}")
    lines.append(f"overall: {verdict_line(r)} — the configuration {r['standing']} ({allowable})")
    return "\n".join(lines)


def _list_scenes() -> None:
    """The built-in scenes and their descriptions, read as text (nothing of the FE is imported)."""
    from importlib import resources

    root = resources.files("rigfem") / "scenes"
    for f in sorted((p for p in root.iterdir() if p.name.endswith(".toml")), key=lambda p: p.name):
        data = tomllib.loads(f.read_text())
        print(f"{f.name[:-5]:32s} {plain(data.get('description', data['linkage'].get('title', '')))}")


class _Verdict(OBSERVER.__class__):
    """The command line's progress, and the summary printed as soon as the verdicts are known."""

    def decided(self, report: dict) -> None:  # before the pictures and files are written
        with above():
            print(_summary(report), flush=True)


def run(args: argparse.Namespace) -> int:
    if args.list:  # a listing is instant: before any of the check's imports
        _list_scenes()
        return 0
    from rigfem.cache import from_environment
    from rigfem.context import Context
    from rigfem.pipeline import Output, Request, run_check

    if args.out is not None:
        check_place("--out", args.out, folder=True)
    request = Request(args.scene, _overrides(args), args.allow_rule_violations, args.author)
    output = Output(Path(args.out) if args.out is not None else None, args.force, not args.no_pictures,
                    args.export_inp)
    ctx = Context(from_environment(), OBSERVER if args.json else _Verdict(), args.solver)
    report = run_check(request, output, ctx)
    if args.json:
        print(json.dumps(report, indent=2))
    out = Path(args.out) if args.out is not None else Path("results") / report["scene"]
    with above():  # on a line of its own, not after the progress line
        wrote(f"{out}{os.sep} (report.md, report.html; rigfem show {out})")
    return EXIT[report["verdict"]]
