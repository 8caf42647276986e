"""Regenerate every results/benchmarks/*.md table and README's figures from the benchmark records.

    python benchmarks/publish.py           # write the tables and README's generated blocks
    python benchmarks/publish.py --check   # exit 1 when a table, README or a record disagrees

README's figures live between ``<!-- NAME:begin -->`` and ``<!-- NAME:end -->`` markers (blocks
of lines) or inside ``<!-- fig:KEY -->…<!-- /fig -->`` spans (one figure in a sentence); both are
rewritten from results/benchmarks/*.json (benchmarks/record.py), never typed by hand.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from record import OUT, REQUIRED, ROOT, summarise
from tables import LE10_TARGET, RENDER, grid_note, grid_rows, hms, le10_outliers, med

README = ROOT / "README.md"
VERIFY = "calculix_verify_final-cm"  #: written by `rigfem verify --against calculix`, not a benchmark
BLOCK = re.compile(r"(<!-- (?P<name>[\w-]+):begin -->\n)(?P<body>.*?)(<!-- (?P=name):end -->)", re.S)
SPAN = re.compile(r"(<!-- fig:(?P<key>[\w-]+) -->)(?P<body>.*?)(<!-- /fig -->)", re.S)


def load(out: Path = OUT) -> dict[str, dict]:
    """Every record the tables and README are made from, by name."""
    return {p.stem: json.loads(p.read_text()) for p in sorted(out.glob("*.json"))
            if p.stem in RENDER or p.stem == VERIFY}


def problems(recs: dict[str, dict]) -> list[str]:
    """Records missing, lacking a required key or raw samples, or whose summaries differ from their samples."""
    out = [f"results/benchmarks/{n}.json: missing (run its benchmark)" for n in RENDER if n not in recs]
    for n, r in recs.items():
        if n == VERIFY:
            continue
        out += [f"results/benchmarks/{n}.json: no {k!r}" for k in REQUIRED if k not in r]
        if not r.get("samples") or not all(r["samples"].values()):
            out.append(f"results/benchmarks/{n}.json: no raw samples")
        elif r.get("summary") != json.loads(json.dumps(summarise(r["samples"]))):
            out.append(f"results/benchmarks/{n}.json: summary differs from its raw samples")
        if not all(k in r.get("machine", {}) for k in ("cores", "cpu", "memory_gib")):
            out.append(f"results/benchmarks/{n}.json: machine lacks cores, cpu or memory")
    return out


def _cmd(rec: dict) -> str:
    return f"`{rec['command']}`"


def figure_rows(recs: dict[str, dict]) -> list[str]:
    """README's Figures table: figure, the command that measured it, the result from its record."""
    c, x, cy, k, dy, le, sw = (recs[n] for n in ("check", "calculix_vs_rigfem", "cycle_vs_calculix", "kinematics",
                                                 "dynamics", "le10", "sweep"))
    v, st, fe = recs[VERIFY], recs["stages"], recs["fe_assembly"]
    rss = [c["summary"][s]["peak_tree_rss_mib"] for s in c["summary"]]
    worst = max(abs(r["peak_rel_diff"]) for r in v["cases"])
    n = cy["params"]["angles"][0]
    lv = le["samples"]["levels"]
    ratios = [med(le, f"{r['size_mm']:g} mm rigfem") / med(le, f"{r['size_mm']:g} mm ccx") for r in lv]
    outl = "; ".join(f"{r['size_mm']:g} mm {r['error_pct']:+.2f} % (a coarse mesh, {r['layers']} layers; "
                     f"CalculiX on it {r['error_ccx_pct']:+.2f} %)"
                     for r in le10_outliers(le)) or "none"
    errs = ", ".join(f"{r['error_pct']:+.2f}" for r in lv)
    pics = st["samples"]["check cold"][0].get("pictures", 0.0)
    one = sw["samples"]["cold, 2 workers"][0]
    rows = [
        ("`rigfem check final-cm`, whole scene (6 parts × 2 modes, all outputs: VTU/PVD, PyVista pictures, HTML)",
         _cmd(c), f"warm caches standard **{med(c, 'standard warm'):.1f} s**, draft **{med(c, 'draft warm'):.1f} s**; "
         f"cold (empty rigfem and numba caches) standard {med(c, 'standard cold'):.1f} s, draft "
         f"{med(c, 'draft cold'):.1f} s; peak RSS of the check's process tree {min(s['min'] for s in rss):.0f}–"
         f"{max(s['max'] for s in rss):.0f} MiB; median of {c['params']['repeats']} separate processes, "
         f"{c['date'][:10]} — results/benchmarks/check.md"),
        (f"rigfem vs CalculiX 2.20, 700 mm rail, curved P2, {x['params']['mesh']['dof'] / 1e3:.0f}k DOF, 1 thread "
         "each", _cmd(x), f"FE wall time ratio rigfem/ccx **{x['derived']['FE wall ratio rigfem / ccx']:.2f}**; "
         f"{x['params']['unit cases']} load cases **{x['derived']['unit cases wall ratio rigfem / ccx']:.2f}** (one "
         f"factorisation); peak σvm agrees to {x['derived']['peak von Mises rel diff']:.0e}, {x['date'][:10]} — "
         "results/benchmarks/calculix_vs_rigfem.md"),
        ("every part case of final-cm re-solved in CalculiX", f"`{v['command']}`",
         f"all {len(v['cases'])} cases within {100 * worst:.4f} % — results/benchmarks/{VERIFY}.md"),
        ("FE assembly and solvers", _cmd(fe), f"assembly {fe['derived']['assembly_speedup']:.1f}× scikit-fem's "
         f"generic form, {fe['date'][:10]} — results/benchmarks/fe_assembly.md"),
        (f"cycle mode vs CalculiX doing the same work: crank rail, same mesh "
         f"({cy['params'][f'{n} angles']['dof'] / 1e3:.0f}k DOF), the same {n} crank angles (N load steps in "
         "CalculiX), von Mises peak per angle", _cmd(cy),
         f"rigfem {med(cy, f'rigfem, {n} angles'):.1f} s vs CalculiX {med(cy, f'ccx, {n} angles'):.1f} s: ratio "
         f"**{cy['derived'][f'rigfem / ccx, {n} angles']:.2f}** (measured, median of {cy['params']['repeats']}); "
         f"peaks agree to {cy['summary'][f'ccx, {n} angles']['max_peak_rel_diff']['max']:.0e} — "
         "results/benchmarks/cycle_vs_calculix.md"),
        ("where the time goes per stage (check cold/warm, a sweep chunk)", _cmd(st),
         f"pictures {pics:.1f} s of the cold check's {st['samples']['check cold'][0]['total (profiled)']:.0f} s "
         "— results/benchmarks/stages.md"),
        ("closed-form kinematics, four-bar, full turn at 5000 angles", _cmd(k),
         f"**{k['derived']['total ms']:.1f} ms** (median of {k['params']['runs']}) — results/benchmarks/kinematics.md"),
        ("linkage dynamics, rig four-bar, one full turn at 5000 angles", _cmd(dy),
         f"closed form **{med(dy, 'closed form, 5000 angles (simulate)', 'wall_ms'):.1f} ms** vs the general solver "
         f"{med(dy, 'general solver, 5000 angles', 'wall_ms'):.1f} ms (same run) — results/benchmarks/dynamics.md, "
         "results/dynamics/"),
        ("speed/accuracy of the fidelity presets", "`rigfem convergence final-cm` (see "
         "`benchmarks/bench_convergence.py`)", "results/convergence/summary.md"),
        ("rail profile sensitivity", "`python benchmarks/rail_profile_study.py --fidelity draft standard`",
         "results/rail_profile/study.md"),
        ("NAFEMS LE10, rigfem vs CalculiX on the same P2 meshes: σyy(D), time and peak RSS vs DOF", _cmd(le),
         f"{len(lv)} meshes, {lv[0]['dof'] / 1e3:.1f}k–{lv[-1]['dof'] / 1e3:.0f}k DOF: σyy(D) "
         f"{errs} % of {LE10_TARGET} MPa; outside 2 %: {outl}; the codes agree "
         f"to {max(abs(r['syy_D_ccx'] / r['syy_D'] - 1) for r in lv):.0e}; FE wall time ratio rigfem/ccx "
         f"{min(ratios):.2f}–{max(ratios):.2f} — results/benchmarks/le10.md, le10.png"),
        ("cost of a 30 mm rig grid on N workers", _cmd(recs["sweep_grid_cost"]),
         "see [Running the sweep on a cluster](#running-the-sweep-on-a-cluster) — "
         "results/benchmarks/sweep_grid_cost.md"),
        ("the whole four-bar sweep, end to end (start-up included)", _cmd(sw),
         f"{one['configurations']:,} configurations, {one['computed']:,} computed: "
         + "; ".join(f"{k} **{hms(med(sw, k))}**" for k in sw["summary"])
         + "".join(f"; efficiency 1 → 2 workers {k.split()[0]} {100 * v:.0f} %" for k, v in sw["derived"].items()
                   if "efficiency" in k)
         + " (runs not listed were not measured: see sweep.md) — results/benchmarks/sweep.md, "
         "results/sweep/"),
    ]
    return ["| figure | command | result |", "|---|---|---|"] + [f"| {a} | {b} | {r} |" for a, b, r in rows]


def spans(recs: dict[str, dict]) -> dict[str, str]:
    """The single figures quoted in README's prose."""
    sw, mt = recs["sweep"], recs["malloc_trim"]
    return {"sweep-2-warm": hms(med(sw, "warm, 2 workers")),
            "sweep-cold-extra": f"{recs['sweep']['derived']['cold - warm, 2 workers (s)']:.0f} s",
            "malloc-trim": f"{100 * mt['derived']['wall with / without - 1']:+.0f} %",
            "malloc-trim-faults": f"{med(mt, 'MALLOC_TRIM_THRESHOLD_=65536', 'minor_faults') / 1e6:.1f} million",
            "kinematics-ms": f"{recs['kinematics']['derived']['total ms']:.1f} ms"}


def blocks(recs: dict[str, dict]) -> dict[str, str]:
    """README's generated blocks of lines."""
    g = recs["sweep_grid_cost"]
    return {"figures": "\n".join(figure_rows(recs)) + "\n",
            "grid-cost": f"Command: {_cmd(g)} (results/benchmarks/sweep_grid_cost.md, {g['date'][:10]}):\n\n"
                         + "\n".join(grid_rows(g)) + "\n\n" + grid_note(g) + "\n"}


def render_readme(text: str, recs: dict[str, dict]) -> str:
    """README with every generated block and span rewritten from the records."""
    b, s = blocks(recs), spans(recs)
    missing = [n for n in b if f"<!-- {n}:begin -->" not in text]
    if missing:
        raise SystemExit(f"README.md: no <!-- {missing[0]}:begin --> block")
    text = BLOCK.sub(lambda m: m[1] + b[m["name"]] + m[4] if m["name"] in b else m[0], text)
    return SPAN.sub(lambda m: m[1] + s[m["key"]] + m[4] if m["key"] in s else m[0], text)


def readme_paths(text: str) -> list[str]:
    """Result files named by README's Figures block that do not exist."""
    m = next((m for m in BLOCK.finditer(text) if m["name"] == "figures"), None)
    body = m["body"] if m else ""
    named = set(re.findall(r"results/[\w./-]+\w", body))
    named |= {"results/benchmarks/" + f for f in re.findall(r", (le10\.png)", body)}
    return sorted(p for p in named if not (ROOT / p).exists())


def outputs(recs: dict[str, dict]) -> dict[Path, str]:
    """Every file this script writes, with its text."""
    out = {OUT / f"{n}.md": render(recs[n]) for n, render in RENDER.items()}
    out[README] = render_readme(README.read_text(), recs)
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
    bad = [f"README.md names {p}, which does not exist" for p in readme_paths(files[README])]
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
