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
from rigfem.cli.progress import OBSERVER
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
    p.add_argument("--fidelity", help="draft | standard | fine (overrides the scene)")
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
    lines = [f"{plain(r['scene'])}: {plain(r['description'])}",
             f"{'part':14s} {'mode':9s} {'peak σvm':>9s} {'crank°':>7s} {'error':>7s} {'util.':>7s}  verdict  where"]
    for p in r["parts"]:
        if p.get("peak_mpa") is None:
            lines.append(f"{p['name']:14s} {p['mode']:9s} {'-':>9s} {'-':>7s} {'-':>7s} {'-':>7s}  "
                         f"{p['verdict'].upper():7s}  {p['notes'][0]}")
            continue
        why = f": {plain(p['reason'])}" if p.get("reason") else ""
        lines.append(f"{p['name']:14s} {p['mode']:9s} {p['peak_mpa']:9.1f} {p['crank_deg']:7.1f} "
                     f"{p['error_pct']:6.1f}% {p['utilisation_pct']:6.1f}%  {p['verdict'].upper():7s}  "
                     f"{p['surface']}{why}")
    lines[0:0] = ([f"WARNING: breaks rig rule {plain(v)} (--allow-rule-violations)" for v in r["rule_violations"]]
                  + [f"ASSUMED: {plain(v)}" for v in r.get("assumed", [])])
    scope = f"; checked {r['left_out']}" if r.get("left_out") else ""
    lines.append(f"overall: {r['verdict'].upper()} (limit {r['limit_mpa']:.0f} MPa{scope})")
    return "\n".join(lines)


class _Verdict(OBSERVER.__class__):
    """The command line's progress, and the summary printed as soon as the verdicts are known."""

    def decided(self, report: dict) -> None:  # before the pictures and files are written
        print(_summary(report), flush=True)


def run(args: argparse.Namespace) -> int:
    from rigfem.cache import from_environment
    from rigfem.context import Context
    from rigfem.pipeline import Output, Request, run_check
    from rigfem.scene import builtin_scenes

    if args.list:
        for name, path in sorted(builtin_scenes().items()):
            data = tomllib.loads(path.read_text())
            print(f"{name:32s} {plain(data.get('description', data['linkage'].get('title', '')))}")
        return 0
    if args.out is not None:
        check_place("--out", args.out, folder=True)
    request = Request(args.scene, _overrides(args), args.allow_rule_violations)
    output = Output(Path(args.out) if args.out is not None else None, args.force, not args.no_pictures,
                    args.export_inp)
    ctx = Context(from_environment(), OBSERVER if args.json else _Verdict(), args.solver)
    report = run_check(request, output, ctx)
    if args.json:
        print(json.dumps(report, indent=2))
    out = Path(args.out) if args.out is not None else Path("results") / report["scene"]
    wrote(f"{out}{os.sep} (report.md, report.html; rigfem show {out})")
    return EXIT[report["verdict"]]
