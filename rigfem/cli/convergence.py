"""``rigfem convergence``: h and p refinement of a check's peak von Mises, with Richardson extrapolation.

``rigfem convergence final-cm`` studies every part of the scene; ``rigfem convergence plate_A``
one part of the reference scene (final-cm).  Writes ``<part>.md``, ``<part>.json`` and an
error-vs-time plot ``<part>.png`` per part under ``--out`` and rebuilds ``summary.md`` there from
every study JSON in the folder.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from rigfem.cli.linkage_args import add_rule_argument
from rigfem.cli.outputs import mark_folder, new_folder, write_file, write_text, wrote
from rigfem.cli.progress import OBSERVER
from rigfem.errors import InputError, check_range, plain
from rigfem import verification  # lazy (lazy_loader): the FE stack loads when a study runs, not for --help
from rigfem.settings import FIDELITY, MODES, PARTS, REFERENCE_SCENE

HELP = "mesh convergence (h and p) of each part's peak von Mises: Richardson limit, order, error vs time"
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = "study written"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("target", nargs="?", default=REFERENCE_SCENE,
                   help=f"scene (file or built-in name) or a part of {REFERENCE_SCENE} (e.g. plate_A)")
    p.add_argument("--mode", help="original | cycle (default both)")
    p.add_argument("--levels", default="4", help="h levels, 3..8 (default 4)")
    p.add_argument("--ratio", default=str(verification.RATIO), help="size ratio between h levels, 1.1..2 (default √2)")
    p.add_argument("--max-gib", default="12", help="refuse an h level predicted above this memory (GiB)")
    p.add_argument("--extra-levels", default=str(verification.EXTEND),
                   help=f"finer h levels added while a peak is not converging, 0..3 (default {verification.EXTEND})")
    p.add_argument("--no-presets", action="store_true", help="h sequence only (no draft/standard/P1 steps)")
    p.add_argument("--out", default="results/convergence",
                   help="folder: a new one, or with --force one rigfem wrote (studies accumulate there)")
    p.add_argument("--force", action="store_true", help="write into an existing --out folder rigfem wrote")
    add_rule_argument(p)
    p.add_argument("--render", action="store_true",
                   help="no computing: re-analyse the study JSONs in --out and rewrite tables, plots, summary")


def _fmt(v, spec: str = ".1f", none: str = "-") -> str:
    return none if v is None else format(v, spec)


def _pct(v) -> str:
    return "-" if v is None else f"{100 * v:+.2f} %"


def table(res: dict) -> str:
    """Markdown table of a part's study: steps, then the extrapolation per mode and quantity."""
    cols = [(m, q) for m in res["modes"] for q in res["modes"][m]]
    name = {"peak_mpa": "peak", "away_mpa": "away"}
    head = "| step | order | size mm | local mm | dirs | DOFs | time s | CPU s | peak RSS MiB |"
    head += "".join(f" {m} {name[q]} MPa | error |" for m, q in cols)
    lines = [f"## {res['part']} ({res['part_def']} {res['params'] or ''})", "", head,
             "|" + "---|" * (9 + 2 * len(cols))]
    for s in res["steps"]:
        row = (f"| {s['label']} | P{s['order']} | {s['size_mm']:.3g} | {s['local_size_mm']:.3g} | "
               f"{s['bearing_directions']} | {s['dofs']} | {s['seconds']:.1f} | {_fmt(s.get('cpu_seconds'))} | "
               f"{_fmt(s['peak_rss_mib'], '.0f')} |")
        for m, q in cols:
            err = res["modes"][m][q].get("errors", {}).get(s["label"])
            row += f" {s['modes'][m][q]:.2f} | {_pct(err)} |"
        lines.append(row)
    lines += ["", "'away': peak away from the I-profile's sharp web-flange corners (fillet_radius = 0 only) "
              f"(nodes farther than {verification.AWAY_MM:g} mm)" if any(q == "away_mpa" for _, q in cols) else "", ""]
    for m in res["modes"]:
        for qty, a in res["modes"][m].items():
            ex = a.get("extrapolation")
            what = "peak" if qty == "peak_mpa" else "peak away from the sharp web-flange corners"
            if ex is None:
                lines.append(f"- **{m}**, {what}: {a['note']}")
                continue
            fin = [s for s in res["steps"] if s["kind"] == "h"][-1]["modes"][m]
            where = f"; finest peak at {fin['surface']} {fin['xyz']}" if qty == "peak_mpa" else ""
            orders = ", ".join(_fmt(o, ".2f") for o in ex["orders"])
            status = ex.get("status", "converged" if ex["order"] else "oscillating")
            if not ex["converging"]:
                lines.append(f"- **{m}**, {what}: **NOT CONVERGING** — {ex['note']} (orders {orders}); "
                             f"no extrapolated value, no preset can meet a target on it{where}")
            elif status == "converged":
                lines.append(f"- **{m}**, {what}: extrapolated **{ex['limit']:.2f} MPa**, observed order "
                             f"{_fmt(ex['order'], '.2f')} (triples coarse→fine: {orders}), GCI(finest) "
                             f"{_pct(ex['gci'])}, asymptotic: {'yes' if ex['asymptotic'] else 'no'}"
                             f"{'; ' + ex['note'] if ex['note'] else ''}{where}")
            else:
                lines.append(f"- **{m}**, {what}: **{status}**, reference = finest level "
                             f"**{ex['limit']:.2f} MPa "
                             f"± {100 * (ex['gci'] or 0):.2f} %** — {ex['note']} (orders {orders}){where}")
    if res.get("directions_note"):
        lines.append(f"- bearing directions: {res['directions_note']}")
    if res["refused"]:
        lines.append(f"- not run (memory): {'; '.join(res['refused'])}")
    return "\n".join(lines) + "\n"


def plot(res: dict, path: Path) -> None:
    """Left: log-log |error| vs time per step (CPU time if every step has it, else wall time);
    right: the peak itself vs DOFs over the h sequence (shows a singular peak rising)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, LogLocator

    cpu = all(s.get("cpu_seconds") for s in res["steps"])
    t_of = (lambda s: s["cpu_seconds"]) if cpu else (lambda s: s["seconds"])
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.5))
    notes = []
    hs_all = [s for s in res["steps"] if s["kind"] == "h"]
    for i, (m, qs) in enumerate(res["modes"].items()):
        for qty, a in qs.items():
            ex = a.get("extrapolation")
            ls = "-" if qty == "peak_mpa" else "--"
            tag = m if qty == "peak_mpa" else f"{m}, away from corners"
            bx.semilogx([s["dofs"] for s in hs_all], [s["modes"][m][qty] for s in hs_all], ls, marker="o",
                        color=f"C{i}", label=tag + ("" if ex and ex["converging"] else " (NOT CONVERGING)"))
            if not ex or not ex["converging"]:
                notes.append(f"{tag}: NOT CONVERGING")
                continue
            hs = [s for s in hs_all if a["errors"][s["label"]] is not None]
            err = [max(abs(a["errors"][s["label"]]), 1e-6) * 100 for s in hs]
            ax.loglog([t_of(s) for s in hs], err, ls, marker="o", color=f"C{i}", label=f"{tag}: h, P2")
            for s in res["steps"]:
                if s["kind"] != "h" and a["errors"][s["label"]] is not None:
                    e = max(abs(a["errors"][s["label"]]), 1e-6) * 100
                    ax.loglog(t_of(s), e, "s" if s["kind"] == "preset" else "^", color=f"C{i}")
                    ax.annotate(s["label"], (t_of(s), e), fontsize=7)
    for p, t in verification.TARGETS.items():
        ax.axhline(100 * t, color="grey", lw=0.6, ls=":")
        ax.annotate(f"{p} target", (0.01, 100 * t), xycoords=("axes fraction", "data"), fontsize=7,
                    va="bottom")
    if ax.get_xscale() == "log":   # nothing converging: no error curve, the axis stays linear
        ax.xaxis.set_minor_locator(LogLocator(subs=(2.0, 3.0, 5.0)))
        for axis in (ax.xaxis.set_major_formatter, ax.xaxis.set_minor_formatter):
            axis(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_xlabel(f"{'CPU' if cpu else 'wall'} time per step (s): mesh + assembly + solves + cycle sweep")
    ax.set_ylabel("|error| vs extrapolated peak (%)")
    ax.set_title(f"{res['part']}: peak von Mises error vs time" + (f"\n{'; '.join(notes)}" if notes else ""),
                 fontsize="small")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small")
    bx.set_xlabel("DOFs (h sequence, P2)")
    bx.set_ylabel("peak von Mises (MPa)")
    bx.set_title(f"{res['part']}: peak vs DOFs", fontsize="small")
    bx.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _abs_err(a: dict, label: str) -> float:
    """|error| of a step, or the reference's own uncertainty (oscillating or noise-limited)."""
    e = a["errors"][label]
    return abs(e) if e is not None else a["extrapolation"]["gci"]


def _conditions(results: list[dict]) -> str:
    """One line on how the times were measured and how busy the machine was."""
    loads = [s["load_avg"] for r in results for s in r["steps"] if s.get("load_avg") is not None]
    busy = (f"1-min load average {min(loads):.1f}–{max(loads):.1f} at the end of the steps that recorded it"
            if loads else "load average not recorded")
    return (f"Machine: {os.cpu_count()} cores shared with other jobs ({busy}); wall time is inflated by "
            "waiting for a core, CPU time (all threads of the step's process) is the steadier figure. "
            "Memory: peak RSS of the step's own spawned process (gmsh, PARDISO are native allocations).")


def _quantities(res: dict):
    """(mode label, analysis, extrapolation) of the peak, and of the peak away from singular edges."""
    for m, qs in res["modes"].items():
        for qty, a in qs.items():
            label = m if qty == "peak_mpa" else f"{m}, away from corners"
            yield label, a, a.get("extrapolation")


def summary(results: list[dict]) -> str:
    """summary.md: per part, mode and preset the cost and the error against the extrapolated peak."""
    lines = ["# Convergence summary: what each preset costs and how accurate it is", "",
             "Error = preset peak vs the Richardson-extrapolated peak of the h sequence (P2, three finest "
             "levels). Targets: " + ", ".join(f"{p} ≤ {100 * t:g} %" for p, t in verification.TARGETS.items()) + ". "
             "Time and memory are per step and cover both modes of a part (one mesh, shared solves). "
             "Presets: " + "; ".join(f"{n}: P{f.order}, {f.size_mm:g}/{f.near_mm:g} mm, "
                                     f"{f.bearing_directions} dirs" for n, f in FIDELITY.items()) + ".",
             "Uncertainty: GCI of the finest h level (Roache, safety factor 1.25). Oscillating and "
             "noise-limited sequences (last changes ≤ 1 %, not growing) have no Richardson limit: their "
             "reference is the finest level, the uncertainty its last change (× 1.25 if noise-limited).",
             "", _conditions(results),
             "", "| part | mode | extrapolated MPa | order | uncertainty | preset | time s | CPU s "
                 "| peak RSS MiB | DOFs | peak MPa | error | target met |",
             "|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---|"]
    for res in results:
        for m, a, ex in _quantities(res):
            if not ex or not ex["converging"]:
                lim, order = "**not converging**", "≤0 / -"
            elif ex["order"] is None:
                lim, order = f"{ex['limit']:.2f} (finest, {ex.get('status', 'oscillating')})", "-"
            else:
                lim, order = f"{ex['limit']:.2f}", _fmt(ex["order"], ".2f")
            gci = _pct(ex["gci"]).lstrip("+") if ex and ex["converging"] else "-"
            for p, v in a.get("presets", {}).items():
                met = {None: "n/a (singular)", True: "yes", False: "**no**"}[v["meets"]]
                err = _pct(v["error"])
                if v["error"] is None and v.get("error_bound") is not None:
                    err = f"±{100 * v['error_bound']:.2f} % (the reference)"
                lines.append(f"| {res['part']} | {m} | {lim} | {order} | {gci} | {p} | {v['seconds']:.1f} | "
                             f"{_fmt(v.get('cpu_seconds'))} | "
                             f"{_fmt(v['peak_rss_mib'], '.0f')} | {v['dofs']} | {v['value']:.2f} | {err} | "
                             f"{met} |")
    old = [r["part"] for r in results if r.get("directions_note")]
    if old:
        lines += ["", f"Bearing directions: the studies of {', '.join(old)} were measured before the "
                      "per-step directions fix: all their steps used 12 directions, so their preset rows give "
                      "the mesh error alone; the direction error (cycle mode) is in sampling.md."]
    lines += ["", "## Coarsest h level meeting each target (P2)", "",
              "Per part and mode, the coarsest level of the h sequence whose peak is within the target "
              "of the extrapolated peak (and every finer level is too); a preset meeting the target on "
              "every part needs sizes no larger than the finest of these.", "",
              "| part | mode | " + " | ".join(f"{p} ≤ {100 * t:g} %" for p, t in verification.TARGETS.items()) + " |",
              "|---|---|" + "---|" * len(verification.TARGETS)]
    for res in results:
        hs = [s for s in res["steps"] if s["kind"] == "h"]
        for m, a, ex in _quantities(res):
            if not ex or not ex["converging"]:
                lines.append(f"| {res['part']} | {m} | " + " | ".join("n/a (not converging)" for _ in verification.TARGETS)
                             + " |")
                continue
            cells = []
            for t in verification.TARGETS.values():
                ok = [s for i, s in enumerate(hs) if all(_abs_err(a, x["label"]) <= t for x in hs[i:])]
                t_s = ok[0].get("cpu_seconds") if ok else None
                cost = (f"{t_s:.0f} s CPU" if t_s else f"{ok[0]['seconds']:.0f} s wall") if ok else ""
                cells.append(f"{ok[0]['size_mm']:.3g}/{ok[0]['local_size_mm']:.3g} mm ({ok[0]['label']}, {cost})"
                             if ok else "none")
            lines.append(f"| {res['part']} | {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _targets(target: str) -> tuple[str, list[str] | None]:
    """(scene, parts) of a CLI target: a part of the reference scene, or a scene."""
    ref = {p for parts in PARTS.values() for p in parts}
    if target in ref:
        return REFERENCE_SCENE, [target]
    return target, None


def _command(a: argparse.Namespace) -> str:
    opts = [f"--mode {a.mode}" if a.mode else "", f"--levels {a.levels}" if a.levels != "4" else "",
            f"--ratio {a.ratio}" if a.ratio != str(verification.RATIO) else "", "--no-presets" if a.no_presets else "",
            f"--max-gib {a.max_gib}" if a.max_gib != "12" else "",
            f"--extra-levels {a.extra_levels}" if a.extra_levels != str(verification.EXTEND) else ""]
    return " ".join(["rigfem convergence", a.target, *[o for o in opts if o]])


def run(args: argparse.Namespace) -> int:
    if args.mode is not None and args.mode not in MODES:
        raise InputError(f"--mode {args.mode!r} must be one of {', '.join(MODES)}")
    n_extra = check_range("--extra-levels", args.extra_levels, 0, 3)
    if n_extra != int(n_extra):
        raise InputError(f"--extra-levels = {args.extra_levels!r} must be a whole number in [0, 3]")
    spec = verification.StudySpec(check_range("--levels", args.levels, 3, 8), check_range("--ratio", args.ratio, 1.1, 2.0),
                                  (args.mode,) if args.mode else None,
                                  check_range("--max-gib", args.max_gib, 0.5, 1024.0, "GiB"),
                                  presets=not args.no_presets, extend=int(n_extra))
    if args.render and not Path(args.out).is_dir():
        raise InputError(f"--out = {args.out!r}: no such folder to render")
    out = new_folder("--out", args.out, args.force or args.render)
    if args.render:
        for path in sorted(out.glob("*.json")):
            res = json.loads(path.read_text())
            if "steps" in res:
                _write(verification.analyse(res), out, path.stem)
    else:
        scene, parts = _targets(args.target)
        from rigfem.cache import from_environment
        from rigfem.job import Request

        request = Request(scene, {"parts": list(parts)} if parts else {}, args.allow_rule_violations)
        job, by_part = verification.scene_cases(request, from_environment())
        settings, broken = job.settings, list(job.rule_violations)
        if args.mode is not None and args.mode not in settings.modes:
            raise InputError(f"--mode {[args.mode]}: no case of this part in that mode (the scene's "
                             f"[check].modes = {list(settings.modes)})")
        for v in broken:
            print(f"WARNING: breaks rig rule {plain(v)} (--allow-rule-violations)", flush=True)
        mark_folder(out)
        for name, cases_for in by_part.items():
            stem = name if args.mode is None else f"{name}_{args.mode}"
            extra = {"scene": scene, "command": _command(args), "rule_violations": broken}

            class Saving(type(OBSERVER)):  # the command line's progress, and each partial study kept
                def partial(self, result: dict, stem: str = stem, extra: dict = extra) -> None:
                    write_text(out / f"{stem}.json", verification.to_json({**result, **extra, "partial": True}))

            res = verification.study(cases_for, settings, spec, Saving())
            print(_write({**res, **extra}, out, stem))
    OBSERVER.stage("summary")
    done = [json.loads(p.read_text()) for p in sorted(out.glob("*.json"))]
    write_text(out / "summary.md", summary([s for s in done if "steps" in s]))
    wrote(out / "summary.md")
    return 0


def _write(res: dict, out: Path, stem: str) -> str:
    """Write <stem>.json, .md and .png; return the Markdown table."""
    write_text(out / f"{stem}.json", verification.to_json(res))
    md = table(res)
    write_text(out / f"{stem}.md", f"# Convergence: {res['scene']} {res['part']}\n\nCommand: "
                                    f"`{res['command']}`\n\n{md}")
    write_file(out / f"{stem}.png", lambda tmp: plot(res, tmp))
    return md
