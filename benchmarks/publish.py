"""Regenerate every results/benchmarks/*.md table and the figures of README and the docs from the records.

    python benchmarks/publish.py           # write the tables and the pages' generated blocks
    python benchmarks/publish.py --check   # exit 1 when a table, a page or a record disagrees

A page's figures (README.md and every docs/**/*.md) live between ``<!-- NAME:begin -->`` and
``<!-- NAME:end -->`` markers (blocks of lines) or inside ``<!-- fig:KEY -->…<!-- /fig -->`` spans
(one figure in a sentence); both are rewritten from results/benchmarks/*.json (benchmarks/record.py)
and results/convergence/*.json, never typed by hand.  Each block and each span appears on exactly one
page (one figure per quantity; another page links to it); ``--check`` fails on a figure that differs
from its record, a block or span on no page or on two, and a result file a figure names that does not
exist.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from record import OUT, REQUIRED, ROOT, summarise
from tables import (LE10_TARGET, RENDER, cache_note, cache_rows, grid_note, grid_rows, hms, le10_outliers, med,
                    perf_note, perf_rows, profiles, timeline_note, timeline_rows)

README = ROOT / "README.md"
DOCS = ROOT / "docs"
#: the reference parts of the convergence study, in the presets table's column order
CONVERGENCE_PARTS = {"crank_rail": "crank rail", "coupler_rail": "coupler rail", "rocker_rail": "rocker rail",
                     "plate_A": "plate", "post_B": "I-profile post"}
VERIFY = "calculix_verify_final-cm"  #: written by `rigfem verify --against calculix`, not a benchmark
COVERAGE = ROOT / "results" / "convergence" / "band_coverage.json"  #: written by benchmarks/band_coverage.py
BLOCK = re.compile(r"(<!-- (?P<name>[\w-]+):begin -->\n)(?P<body>.*?)(<!-- (?P=name):end -->)", re.S)
SPAN = re.compile(r"(<!-- fig:(?P<key>[\w-]+) -->)(?P<body>.*?)(<!-- /fig -->)", re.S)


def load(out: Path = OUT) -> dict[str, dict]:
    """Every record the tables and README are made from, by name."""
    recs = {p.stem: json.loads(p.read_text()) for p in sorted(out.glob("*.json"))
            if p.stem in RENDER or p.stem == VERIFY}
    if COVERAGE.is_file():  # the error band's coverage study keeps its own record (every raw case, date, commit)
        recs["band_coverage"] = json.loads(COVERAGE.read_text())
    conv = {n: ROOT / "results" / "convergence" / f"{n}.json" for n in CONVERGENCE_PARTS}
    if all(p.is_file() for p in conv.values()):  # written by `rigfem convergence PART`
        recs["convergence"] = {n: json.loads(p.read_text()) for n, p in conv.items()}
    return recs


#: record name -> the command that writes it (quoted in README while a record is missing)
COMMANDS = {
    "check": "python benchmarks/bench_check.py --repeats 3 --fidelity standard draft",
    "calculix_vs_rigfem": "python benchmarks/bench_calculix.py --repeats 3 --threads 1 --cases 4",
    "fe_assembly": "python benchmarks/bench_fe.py",
    "cycle_vs_calculix": "python benchmarks/bench_cycle_calculix.py --fidelity draft --angles 12 --repeats 3",
    "stages": "python benchmarks/profile_stages.py --fidelity standard --chunk 64",
    "timeline": "python benchmarks/profile_timeline.py",
    "kinematics": "python benchmarks/bench_kinematics.py", "dynamics": "python benchmarks/bench_dynamics.py",
    "le10": "python benchmarks/bench_le10.py --sizes 400 283 200 141 100",
    "sweep_grid_cost": "python benchmarks/sweep_grid_cost.py --every 40",
    "sweep": "python benchmarks/bench_sweep.py --workers 2 1", "malloc_trim": "python benchmarks/bench_malloc_trim.py",
    "band_coverage": "python benchmarks/band_coverage.py", "perf": "python benchmarks/bench_perf.py",
    "bad_inputs": "python benchmarks/bad_inputs.py",
    "cache_kinds": "python benchmarks/bench_cache.py --repeats 3",
    "same_results": "python benchmarks/bench_same_results.py --baseline 450ffeb",
    "pardiso": "python benchmarks/bench_pardiso.py --repeats 3",
    "mesh": "python benchmarks/bench_mesh.py --repeats 3",
    "adaptive": "python benchmarks/bench_adaptive.py --fidelity standard draft",
    "levers": "mkdir -p /tmp/base && git archive e5e90b5 | tar -x -C /tmp/base; "
              "python benchmarks/bench_levers.py --label before --src /tmp/base; "
              "python benchmarks/bench_levers.py --label after"}



def problems(recs: dict[str, dict]) -> list[str]:
    """Records lacking a required key or raw samples, or whose summaries differ from their samples."""
    out = []
    for n, r in recs.items():
        if n in (VERIFY, "band_coverage", "convergence"):
            continue
        out += [f"results/benchmarks/{n}.json: no {k!r}" for k in REQUIRED if k not in r]
        smp = r.get("samples")
        if not isinstance(smp, dict) or not smp or not all(isinstance(v, list) and v for v in smp.values()):
            out.append(f"results/benchmarks/{n}.json: no raw samples")
        elif r.get("summary") != json.loads(json.dumps(summarise(r["samples"]))):
            out.append(f"results/benchmarks/{n}.json: summary differs from its raw samples")
        if not isinstance(r.get("machine"), dict) or not {"cores", "cpu", "memory_gib"} <= set(r["machine"]):
            out.append(f"results/benchmarks/{n}.json: machine lacks cores, cpu or memory")
    return out


def _missing(name: str) -> str:
    return f"not measured yet in the dated record format: run `{COMMANDS[name]}`"


#: where another record measures the same quantity, the figure is the performance table's (issue 26's record,
#: re-measured as a whole): a row of another record names the table instead of quoting its own older figure
PERF_PAGE = "[the performance table](#goals)"


def _check(c: dict) -> str:
    """The check record's row: its cold and warm draft times are the performance table's rows (re-measured
    there), so the row points to them and keeps what only it holds (the whole scene's outputs)."""
    return (f"draft cold and warm: see {PERF_PAGE} (`rigfem check final-cm --force --fidelity draft`, the same "
            f"work, re-measured); this record ({c['date'][:10]}) keeps the runs' samples — results/benchmarks/check.md")


def _calculix(x: dict) -> str:
    d = x["derived"]
    return (f"{x['params']['mesh']['dof']:,} DOF: FE wall time ratio rigfem/ccx of one solve: see {PERF_PAGE}; "
            f"{x['params']['unit cases']} load cases "
            f"**{d['unit cases wall ratio rigfem / ccx']:.2f}** (one "
            f"factorisation); peak σvm agrees to {d['peak von Mises rel diff']:.0e}; median of "
            f"{x['params']['repeats']}, {x['date'][:10]} — results/benchmarks/calculix_vs_rigfem.md")


def _cycle(cy: dict) -> str:
    n = cy["params"]["angles"][0]
    return (f"{n} crank angles, {cy['params'][f'{n} angles']['dof']:,} DOF: rigfem {med(cy, f'rigfem, {n} angles'):.1f}"
            f" s vs CalculiX {med(cy, f'ccx, {n} angles'):.1f} s: ratio "
            f"**{cy['derived'][f'rigfem / ccx, {n} angles']:.2f}** (both measured, median of "
            f"{cy['params']['repeats']}); peaks agree to "
            f"{cy['summary'][f'ccx, {n} angles']['max_peak_rel_diff']['max']:.0e} — "
            "results/benchmarks/cycle_vs_calculix.md")


def _le10(le: dict) -> str:
    lv = le["samples"]["levels"]
    ratios = [med(le, f"{r['size_mm']:g} mm rigfem") / med(le, f"{r['size_mm']:g} mm ccx") for r in lv]
    outl = "; ".join(f"{r['size_mm']:g} mm {r['error_pct']:+.2f} % (a coarse mesh, {r['layers']} layers; "
                     f"CalculiX on it {r['error_ccx_pct']:+.2f} %)" for r in le10_outliers(le)) or "none"
    errs = ", ".join(f"{r['error_pct']:+.2f}" for r in lv)
    return (f"{len(lv)} meshes, {lv[0]['dof'] / 1e3:.1f}k–{lv[-1]['dof'] / 1e3:.0f}k DOF: σyy(D) {errs} % of "
            f"{LE10_TARGET} MPa; outside 2 %: {outl}; the codes agree to "
            f"{max(abs(r['syy_D_ccx'] / r['syy_D'] - 1) for r in lv):.0e}; FE wall time ratio rigfem/ccx "
            f"{min(ratios):.2f}–{max(ratios):.2f} — results/benchmarks/le10.md, le10.png")


def _pardiso(p: dict) -> str:
    """README cell of the PARDISO settings record: the solve, analysis + numeric factorisation
    (medians) and memory of each setting against rigfem's."""
    from bench_pardiso import LABELS

    mkl, mine, csr = (LABELS[k] for k in ("mkl", "rigfem", "csr"))
    fact = {k: med(p, k, "analysis_s") + med(p, k, "factorise_s") for k in (mkl, mine, csr)}
    solve = {k: med(p, k, "solve_s") for k in (mkl, mine, csr)}
    mem = {k: med(p, k, "peak_rss_growth_kib") / 1024 for k in (mkl, mine, csr)}
    n = p["params"]["rhs"]
    return (f"rigfem's settings: analysis + factorisation {fact[mine]:.2f} s, a solve of {n} loads "
            f"{solve[mine]:.2f} s, peak memory growth {mem[mine]:.0f} MiB; without the variable blocks "
            f"{fact[csr]:.2f} s, {solve[csr]:.2f} s, {mem[csr]:.0f} MiB; MKL's defaults {fact[mkl]:.2f} s, "
            f"{solve[mkl]:.2f} s, {mem[mkl]:.0f} MiB — results/benchmarks/pardiso.md")


def _sweep(sw: dict) -> str:
    one = next(iter(sw["samples"].values()))[0]
    own = [k for k in sw["summary"] if "2 workers" not in k]  # 2 workers: the performance table's row
    return (f"{one['configurations']:,} configurations, {one['computed']:,} computed: 2 workers, cold and warm: see "
            f"{PERF_PAGE}; " + "; ".join(f"{k} **{hms(med(sw, k))}**" for k in own)
            + f" (the runs measured, {sw['date'][:10]}) — results/benchmarks/sweep.md, results/sweep/")


def _timeline(t: dict) -> str:
    """The cold check's FE and report shares (benchmarks/profile_timeline.py)."""
    from tables import timeline_group

    r = t["samples"].get("check cold", [None])[0]
    if r is None:
        return "results/benchmarks/timeline.md"
    fe = sum(s["seconds"] for s in r["stages"] if timeline_group(s["stage"]).startswith("FE"))
    rep = sum(s["seconds"] for s in r["stages"] if s["stage"].startswith(("report", "verdict known")))
    return (f"cold standard check {r['wall_s']:.0f} s: FE {fe:.0f} s, the report after the verdict {rep:.0f} s — "
            "results/benchmarks/timeline.md")


#: the figures tables (performance and verification pages): (record, figure, result from the record)
ROWS = [
    ("check", "`rigfem check final-cm --force`, whole scene (6 parts × 2 modes, all outputs: VTU/PVD, PyVista pictures, "
     "HTML)", _check),
    ("calculix_vs_rigfem", "rigfem vs CalculiX 2.20, 700 mm rail, curved P2, 1 thread each", _calculix),
    (VERIFY, "every part case of final-cm re-solved in CalculiX",
     lambda v: f"all {len(v['cases'])} cases within {100 * max(abs(r['peak_rel_diff']) for r in v['cases']):.4f} % "
               f"— results/benchmarks/{VERIFY}.md"),
    ("fe_assembly", "FE assembly and solvers",
     lambda f: f"assembly {f['derived']['assembly_speedup']:.1f}× scikit-fem's generic form, {f['date'][:10]} — "
               "results/benchmarks/fe_assembly.md"),
    ("cycle_vs_calculix", "cycle mode vs CalculiX doing the same work: crank rail, the same mesh and the same N "
     "crank angles (N load steps in CalculiX), von Mises peak per angle", _cycle),
    ("stages", "where the time goes per stage (check cold/warm, a sweep chunk)",
     lambda st: f"pictures {st['samples']['check cold'][0].get('pictures', 0.0):.1f} s of the cold check's "
                f"{st['samples']['check cold'][0]['total (profiled)']:.0f} s — results/benchmarks/stages.md"),
    ("timeline", "a command's stages on a clock, children included (check cold and warm, draft, synthesize "
     "--rig, sweep): where the wall time and the memory go", _timeline),
    ("same_results", "the reference scenes' verdicts and peaks with the code before issue 41's work and after it, the "
     "same meshes, 1 thread",
     lambda r: f"largest peak difference **{r['derived']['largest peak difference before -> after']:.1e}** "
               f"(run to run {r['derived']['largest peak difference run to run'] or 0:.1e}); verdicts and meshes the "
               f"same: {'yes' if r['derived']['verdicts and meshes the same'] else '**no**'}, "
               f"{r['derived']['part cases compared']} part cases, {r['date'][:10]} — results/benchmarks/same_results.md"),
    ("kinematics", "closed-form kinematics, four-bar, full turn at 5000 angles",
     lambda k: f"**{k['derived']['total ms']:.1f} ms** (median of {k['params']['runs']}) — "
               "results/benchmarks/kinematics.md"),
    ("dynamics", "linkage dynamics, rig four-bar, one full turn at 5000 angles",
     lambda d: f"closed form **{med(d, 'closed form, 5000 angles (simulate)', 'wall_ms'):.1f} ms** vs the general "
               f"solver {med(d, 'general solver, 5000 angles', 'wall_ms'):.1f} ms (same run) — "
               "results/benchmarks/dynamics.md, results/dynamics/"),
    ("adaptive", "verdict-driven refinement vs fixed preset meshes, final-cm, per part: DOF, s, peak, verdict",
     lambda a: "wall after / before: " + ", ".join(f"{f} {a['derived'][f + ': wall after / before']:.2f}"
                                                     for f in a["params"]["fidelity"])
               + f"; every part consistent: {'yes' if a['derived']['every part consistent'] else '**no**'} — "
                 "results/benchmarks/adaptive.md"),
    (None, "speed/accuracy of the fidelity presets", "`rigfem convergence final-cm --force` (see "
     "`benchmarks/bench_convergence.py`)", "results/convergence/summary.md"),
    ("band_coverage", "coverage of the peaks' error band (an estimate) per preset, and its calibration",
     lambda b: ("on 31 held-out closed-form geometries, per level: " + ", ".join(
                    f"{k} {v['hits']}/{v['n']} (95 % lower bound {v['lower_bound_pct']:.1f} %)"
                    for k, v in b["held_out"]["levels"].items()) + "; on the calibration's cases, "
                if "held_out" in b else "") + "raw ZZ estimate: " + ", ".join(f"{k} {v['coverage_raw_pct']:.0f} %" for k, v in b["coverage"].items())
               + "; calibrated (factor per element order: " + ", ".join(f"P{o} × {f:g}" for o, f in
                                                                     b["calibration"].items())
               + "): " + ", ".join(f"{k} {v['coverage_pct']:.0f} %" for k, v in b["coverage"].items())
               + f" ({b['date_utc'][:10]}) — results/convergence/band_coverage.md"),
    (None, "rail profile sensitivity", "`python benchmarks/rail_profile_study.py --fidelity draft standard`",
     "results/rail_profile/study.md"),
    ("le10", "NAFEMS LE10, rigfem vs CalculiX on the same P2 meshes: σyy(D), time and peak RSS vs DOF", _le10),
    ("sweep_grid_cost", "cost of a 30 mm rig grid on N workers",
     lambda g: "see [Running the sweep on a cluster](guide/sweep.md#running-the-sweep-on-a-cluster) — "
               "results/benchmarks/sweep_grid_cost.md"),
    ("sweep", "the whole four-bar sweep, `rigfem sweep --four-bar`, end to end (start-up included)", _sweep),
    ("pardiso", "MKL PARDISO's defaults, and rigfem's settings without the variable blocks, against rigfem's "
     "settings on a 1000 mm rail (no refinement inside PARDISO, variable blocks)", _pardiso),
    ("mesh", "meshing the check's parts at every ladder level (final-cm, standard): gmsh's default precision of "
     "the 1D size integration against rigfem's",
     lambda m: f"all meshes {m['derived']['seconds, all meshes: gmsh / rigfem']:.2f}× faster at rigfem's (the 1D "
               f"step {m['derived']['1D seconds, all meshes: gmsh / rigfem']:.1f}×); tet counts within "
               f"{100 * m['derived']['largest tet count change']:.1f} % — results/benchmarks/mesh.md"),
    ("malloc_trim", "Dask's MALLOC_TRIM_THRESHOLD_ on a sweep chunk",
     lambda m: f"{100 * m['derived']['wall with / without - 1']:+.0f} % wall time with it — "
               "results/benchmarks/malloc_trim.md"),
]


#: records whose rows are on the verification page (docs/verification.md); every other row is a performance figure
VERIFICATION_ROWS = {VERIFY, "band_coverage", "le10", "speed/accuracy of the fidelity presets", "rail profile sensitivity"}


def figure_rows(recs: dict[str, dict], page: str = "performance") -> list[str]:
    """A figures table (``page``: performance or verification): figure, the command that measured it, the
    result from its record."""
    out = ["| figure | command | result |", "|---|---|---|"]
    for name, figure, *how in ROWS:
        if ((name or figure) in VERIFICATION_ROWS) != (page == "verification"):
            continue
        if name is None:
            out.append(f"| {figure} | {how[0]} | {how[1]} |")
        elif name in recs:
            out.append(f"| {figure} | `{recs[name]['command']}` | {how[0](recs[name])} |")
        else:
            out.append(f"| {figure} | `{COMMANDS[name]}` | {_missing(name)} |")
    return out


def _pct(x: float) -> str:
    """A signed percentage as the presets table writes it (a true minus sign)."""
    return (f"{100 * x:+.2f}" if abs(x) < 1e-3 else f"{100 * x:+.1f}").replace("-", "−")


def _preset_cell(res: dict, preset: str) -> str:
    """One part's cell of a preset's row: error original / cycle mode (%), CPU time of the step."""
    errs, sec = [], None
    for mode in ("original", "cycle"):
        a = res["modes"][mode]["peak_mpa"]
        ex, v = a.get("extrapolation"), a["presets"][preset]
        sec = v.get("cpu_seconds") or v["seconds"]
        if not ex or not ex["converging"]:
            errs.append("n.c.")
        elif v["error"] is None:
            errs.append(f"±{100 * v['error_bound']:.2g}")
        else:
            errs.append(_pct(v["error"]))
    return f"{errs[0]} / {errs[1]} %, {sec:.0f} s"


def _p1_cell(res: dict) -> str:
    out = []
    for mode in ("original", "cycle"):
        a = res["modes"][mode]["peak_mpa"]
        e = a["errors"].get("P1@standard")
        out.append("—" if e is None or not (a.get("extrapolation") or {}).get("converging") else f"{100 * e:+.0f}"
                   .replace("-", "−"))
    return " / ".join(out) + ("" if out[1] == "—" else " %")


def preset_rows(conv: dict[str, dict]) -> list[str]:
    """The presets' errors against the converged peaks, per reference part (results/convergence/*.json)."""
    from rigfem.settings import FIDELITY
    from rigfem.verification.convergence import TARGETS

    out = ["| preset | mesh | " + " | ".join(CONVERGENCE_PARTS.values()) + " | target |",
           "|---|---|" + "---|" * len(CONVERGENCE_PARTS) + "---|"]
    for name, f in FIDELITY.items():
        mesh = f"P{f.order}, {f.size_mm:g} mm, {f.near_mm:g} mm at loaded interfaces, {f.bearing_directions} directions"
        out.append(f"| `{name}` | {mesh} | " + " | ".join(_preset_cell(conv[n], name) for n in CONVERGENCE_PARTS)
                   + f" | {100 * TARGETS[name]:g} % |")
    out.append("| P1 | on the standard mesh | " + " | ".join(_p1_cell(conv[n]) for n in CONVERGENCE_PARTS) + " | — |")
    return out


def _p1_low(conv: dict[str, dict]) -> str:
    errs = [-100 * r["modes"][m]["peak_mpa"]["errors"]["P1@standard"] for r in conv.values() for m in r["modes"]
            if (r["modes"][m]["peak_mpa"].get("extrapolation") or {}).get("converging")
            and r["modes"][m]["peak_mpa"]["errors"].get("P1@standard") is not None]
    return f"{min(errs):.0f}–{max(errs):.0f} %"


def spans(recs: dict[str, dict]) -> dict[str, str]:
    """The single figures quoted in the pages' prose (a missing record says how to make it)."""
    p, mt, k, conv = recs.get("perf", {}), recs.get("malloc_trim"), recs.get("kinematics"), recs.get("convergence")
    out = {"sweep-2": _missing("perf"), "malloc-trim": _missing("malloc_trim"),
           "kinematics-ms": f"({_missing('kinematics')})",
           "p1-low": "(not measured yet: run `rigfem convergence PART` for each reference part)",
           "coupler-cycle": "(not measured yet: run `rigfem convergence coupler_rail`)",
           "coupler-levels": "(not measured yet: run `rigfem convergence coupler_rail`)"}
    if {"sweep cold", "sweep warm"} <= set(p.get("summary", {})):  # the performance table's figure, quoted
        out["sweep-2"] = (f"{hms(med(p, 'sweep cold'))} cold, {med(p, 'sweep warm'):.1f} s with warm caches "
                          f"([performance](../performance.md#goals))")
    if mt:
        faults = med(mt, "MALLOC_TRIM_THRESHOLD_=65536", "minor_faults")
        out["malloc-trim"] = (f"{100 * mt['derived']['wall with / without - 1']:+.0f} %, {faults / 1e6:.1f} million "
                              f"minor faults per chunk: `{mt['command']}`, results/benchmarks/malloc_trim.md")
    if k:
        out["kinematics-ms"] = f"{k['derived']['total ms']:.1f} ms"
    if conv:
        out["p1-low"] = _p1_low(conv)
        out |= _not_converging(conv)
    b = recs.get("band_coverage")
    out["band-draft-factor"] = (f"{b['coverage']['draft']['largest_required_factor']:.2f}" if b else
                                f"(not measured yet: run `{COMMANDS['band_coverage']}`)")
    return out


def _not_converging(conv: dict[str, dict]) -> dict[str, str]:
    """The coupler rail's cycle-mode peak, which does not converge: its finest value against the limit, and
    the sequence over the h levels (results/convergence/coupler_rail.json)."""
    from rigfem.material import get_material  # the limit: σu/2 of the rig steel

    hs = [st["modes"]["cycle"]["peak_mpa"] for st in conv["coupler_rail"]["steps"] if st["kind"] == "h"]
    limit = get_material("rig_steel").sigma_u / 2
    return {"coupler-cycle": f"{hs[-1]:.1f} MPa, {100 * hs[-1] / limit:.0f} % of the limit",
            "coupler-levels": " → ".join(f"{v:.2f}" for v in hs) + " MPa"}


def blocks(recs: dict[str, dict]) -> dict[str, str]:
    """The pages' generated blocks of lines."""
    g = recs.get("sweep_grid_cost")
    grid = (f"Command: `{g['command']}` (results/benchmarks/sweep_grid_cost.md, {g['date'][:10]}):\n\n"
            + "\n".join(grid_rows(g)) + "\n\n" + grid_note(g) + "\n") if g else _missing("sweep_grid_cost") + ".\n"
    p = recs.get("perf")
    perf = (f"Command: `{COMMANDS['perf']}` (this record: `{p['command']}`):\n\n" + "\n".join(perf_rows(p)) + "\n\n"
            + perf_note(p) + "\n" + "".join(f"\n{x}\n" for x in profiles(p))) if p else _missing("perf") + ".\n"
    conv = recs.get("convergence")
    presets = ("Commands: `rigfem convergence PART` for each part (results/convergence/PART.json):\n\n"
               + "\n".join(preset_rows(conv)) + "\n") if conv else "not measured yet: run `rigfem convergence PART`.\n"
    c = recs.get("cache_kinds")
    cache = (f"Command: `{c['command']}` (results/benchmarks/cache_kinds.md):\n\n" + "\n".join(cache_rows(c))
             + "\n\n" + cache_note(c) + "\n") if c else _missing("cache_kinds") + ".\n"
    t = recs.get("timeline")
    where = (f"Command: `{t['command']}` (results/benchmarks/timeline.md, {t['date'][:10]}, commit "
             f"{t['commit']['sha'][:10]}):\n\n" + "\n".join(timeline_rows(t)) + "\n\n" + timeline_note(t) + "\n") if t \
        else _missing("timeline") + ".\n"
    return {"cache-kinds": cache, "perf-figures": "\n".join(figure_rows(recs, "performance")) + "\n",
            "verification-figures": "\n".join(figure_rows(recs, "verification")) + "\n",
            "grid-cost": grid, "performance": perf, "preset-errors": presets, "timeline": where}


def pages() -> list[Path]:
    """README and every page of the docs: the files whose figures this script writes."""
    return [README, *sorted(DOCS.rglob("*.md"))]


def markers(text: str) -> list[str]:
    """The blocks and spans a page holds, by name (``block:NAME``, ``fig:KEY``)."""
    return [f"block:{m['name']}" for m in BLOCK.finditer(text)] + [f"fig:{m['key']}" for m in SPAN.finditer(text)]


def placement(texts: dict[Path, str], recs: dict[str, dict]) -> list[str]:
    """Each generated block and span on exactly one page: one figure per quantity, and none forgotten."""
    where: dict[str, list[str]] = {}
    for path, text in texts.items():
        for k in markers(text):
            where.setdefault(k, []).append(str(path.relative_to(ROOT)))
    known = {f"block:{n}" for n in blocks(recs)} | {f"fig:{k}" for k in spans(recs)}
    bad = [f"{k} is on no page (README.md, docs/)" for k in sorted(known - set(where))]
    bad += [f"{k} is on {len(v)} pages ({', '.join(v)}): one figure per quantity, link to the one page"
            for k, v in sorted(where.items()) if len(v) > 1]
    bad += [f"{k} on {', '.join(v)} has no renderer in benchmarks/publish.py" for k, v in sorted(where.items())
            if k not in known]
    return bad


def render_page(text: str, recs: dict[str, dict]) -> str:
    """A page with every generated block and span it holds rewritten from the records."""
    b, s = blocks(recs), spans(recs)
    text = BLOCK.sub(lambda m: m[1] + b[m["name"]] + m[4] if m["name"] in b else m[0], text)
    return SPAN.sub(lambda m: m[1] + s[m["key"]] + m[4] if m["key"] in s else m[0], text)


def named_paths(text: str) -> list[str]:
    """Result files named by a page's figures tables that do not exist."""
    body = "".join(m["body"] for m in BLOCK.finditer(text) if m["name"].endswith("figures"))
    named = set(re.findall(r"results/[\w./-]+\w", body))
    named |= {"results/benchmarks/" + f for f in re.findall(r", (le10\.png)", body)}
    return sorted(p for p in named if not (ROOT / p).exists())


def outputs(recs: dict[str, dict]) -> dict[Path, str]:
    """Every file this script writes, with its text."""
    out = {OUT / f"{n}.md": render(recs[n]) for n, render in RENDER.items() if n in recs}
    for page in pages():
        text = page.read_text()
        if markers(text):
            out[page] = render_page(text, recs)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="change nothing; exit 1 when a file is out of date")
    a = ap.parse_args(argv)
    recs = load()
    bad = problems(recs)
    if bad:
        print("\n".join(bad), file=sys.stderr)
        return 1
    files = outputs(recs)
    stale = [p for p, t in files.items() if not p.is_file() or p.read_text() != t]
    bad = placement({p: t for p, t in files.items() if p.suffix == ".md" and OUT not in p.parents}, recs)
    bad += [f"{p.relative_to(ROOT)} names {q}, which does not exist" for p, t in files.items()
            if OUT not in p.parents for q in named_paths(t)]
    if a.check:
        bad += [f"{p.relative_to(ROOT)} differs from its records: run python benchmarks/publish.py" for p in stale]
    else:
        for p in stale:
            p.write_text(files[p])
            print(f"wrote {p.relative_to(ROOT)}")
    print("\n".join(bad), file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
