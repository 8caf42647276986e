"""The results/benchmarks/*.md tables, rendered from the benchmark records (benchmarks/record.py) only."""

from __future__ import annotations

from collections.abc import Callable

#: the reference stress of NAFEMS LE10 at point D, MPa (rigfem.verification.le10.TARGET_SYY; not imported:
#: rendering must not load the FE stack); tests/test_figures.py checks the two agree
LE10_TARGET = -5.38


def med(rec: dict, series: str, field: str = "wall_s") -> float:
    """Median of ``field`` over the samples of ``series`` (from the record's summary)."""
    return rec["summary"][series][field]["median"]


def rng(rec: dict, series: str, field: str = "wall_s", fmt: str = ".1f") -> str:
    """``median (min–max)`` of a series, or the median alone for one sample."""
    s = rec["summary"][series][field]
    return f"{s['median']:{fmt}}" + (f" ({s['min']:{fmt}}–{s['max']:{fmt}})" if s["n"] > 1 else "")


def hms(s: float) -> str:
    """Seconds as s, min or h."""
    return f"{s / 3600:.1f} h" if s >= 3600 else f"{s / 60:.1f} min" if s >= 60 else f"{s:.0f} s"


def head(rec: dict, title: str) -> list[str]:
    """Title, command, date, commit, machine and load average of a record."""
    m, c = rec["machine"], rec["commit"]
    return [f"# {title}", "", f"Command: `{rec['command']}`  ",
            f"Recorded {rec['date']} at commit {c['sha'][:10]}{' (work tree modified)' if c['dirty'] else ''} on "
            f"{m['cores']} × {m['cpu']}, {m['memory_gib']:.1f} GiB, Python {m['python']}; load average "
            f"{rec['load'][0]:.2f} at the end (the machine is shared: wall times include waiting for a core).  "
            f"Raw samples: results/benchmarks/{rec['name']}.json.", ""]


def check(rec: dict) -> str:
    p = rec["params"]
    lines = head(rec, f"`rigfem check {p['scene']}`: wall time and peak memory, cold and warm caches")
    lines += [f"Each run a separate process; median (min–max) of {p['repeats']} runs.  Cold: empty rigfem cache "
              "and empty numba cache (mesh, compile, assemble, factorise, solve).  Warm: meshes, unit solutions "
              "and compiled kernels from the caches.  Peak memory: the peak RSS of the check's own process tree "
              "(sum over its processes, polled every 50 ms).", "",
              "| fidelity | cache | wall s | peak tree RSS MiB | load average at the starts |",
              "|---|---|---:|---:|---|"]
    for fid in p["fidelity"]:
        for c in ("cold", "warm"):
            s = f"{fid} {c}"
            loads = ", ".join(f"{x['load_before'][0]:.1f}" for x in rec["samples"][s])
            lines.append(f"| {fid} | {c} | {rng(rec, s)} | {rng(rec, s, 'peak_tree_rss_mib', '.0f')} | {loads} |")
    lines += [""] + [f"{k}: {v:.2f}" + "  " for k, v in rec["derived"].items()]
    return "\n".join(lines) + "\n"


def sweep(rec: dict) -> str:
    lines = head(rec, "The whole four-bar sweep, end to end (`rigfem sweep --four-bar`)")
    one = next(iter(rec["samples"].values()))[0]
    lines += [f"{one['configurations']:,} configurations, {one['computed']:,} computed; each run a separate "
              "`rigfem sweep --four-bar --workers W --quiet` process into a fresh folder: start-up, enumeration, "
              "unit solutions, the local Dask cluster and the report included; one thread per process.  Cold: "
              "empty rigfem and numba caches; warm: the caches the cold run filled.  Peak memory: the sweep's "
              "process tree (workers included; pages they share are counted once per process).", "",
              "| run | wall | wall s | peak tree RSS MiB | failing configurations |", "|---|---:|---:|---:|---:|"]
    for s, rows in rec["samples"].items():
        lines.append(f"| {s} | {hms(med(rec, s))} | {rng(rec, s, fmt='.0f')} | "
                     f"{rng(rec, s, 'peak_tree_rss_mib', '.0f')} | {rows[0]['fail']} |")
    lines += [""] + [f"{k}: {100 * v:.0f} % (t1 / (2 t2), start-up included)  " if "efficiency" in k
                     else f"What a cold cache adds once, {k}: {v:.0f} s  " for k, v in rec["derived"].items()]
    missing = [f"{c}, {w} workers" for w in (2, 1) for c in ("cold", "warm")
               if f"{c}, {w} workers" not in rec["samples"]]
    if missing:
        lines += ["", f"Not measured in this record (the benchmark was stopped before them): {', '.join(missing)}."]
    return "\n".join(lines) + "\n"


def sweep_grid_cost(rec: dict) -> str:
    d = rec["derived"]
    lines = head(rec, "Sweep cost of a finer rig grid (four-bar, draft)")
    lines += ["| hole pitch | lengths b2 × b3 × b4 × d | configurations on the rig | with FE check (full turn) |",
              "|---|---|---|---|"]
    for c in d["counts"].values():
        lines.append(f"| {c['pitch_mm']:g} mm | {' × '.join(map(str, c['lengths']))} | {c['mountable']:,} | "
                     f"{c['fe_checked']:,} |")
    lines += ["", *grid_rows(rec), "", grid_note(rec)]
    return "\n".join(lines) + "\n"


def grid_rows(rec: dict) -> list[str]:
    """The projection table (also README's, under "Running the sweep on a cluster")."""
    d = rec["derived"]
    ns = list(next(iter(d["projected_s"].values())))
    out = ["| hole pitch | four-bars on the rig | with an FE check (crank turns fully) | per configuration | "
           + " | ".join(f"N = {n}" for n in ns) + " |", "|---|---|---|---|" + "---|" * len(ns)]
    for pitch, c in d["counts"].items():
        out.append(f"| {pitch} mm{' (the rig)' if pitch == '60' else ''} | {c['mountable']:,} | {c['fe_checked']:,} | "
                   f"{d['per_config_s'] * 1e3:.0f} ms, measured | "
                   + " | ".join(hms(v) for v in d["projected_s"][pitch].values()) + " |")
    return out


def grid_note(rec: dict) -> str:
    """How the projection is made, with the figures it uses and where they come from."""
    d, s = rec["derived"], rec["samples"]["serial draft sweep of the subset"][0]
    eff = d["efficiency (sweep record, warm 1 -> 2 workers)"]
    return (f"Projection T(N) = T_cold + n_FE · t / (N · e): t = {d['per_config_s'] * 1e3:.0f} ms, the "
            f"per-configuration time of a serial draft sweep of {s['configurations']} configurations spread over "
            f"the grid (measured here); T_cold = {d['cold build (sweep record, cold - warm, 2 workers) s']:.0f} s, "
            f"what a cold cache adds to the whole 60 mm sweep with two workers (meshes, unit solutions, compiled "
            f"kernels; a 30 mm rail has twice the holes, so a lower bound for it) and " + (
                f"e = {100 * eff:.0f} %, the warm 1 → 2 local-worker efficiency with start-up, held for every N > 1"
                if eff is not None else "no N > 1: the sweep record has no 1-worker run, so no measured efficiency")
            + f": both from results/benchmarks/sweep.json ({d['sweep record']['date']}).  The rows without FE "
            "(rules and dynamics only) are left out.")


def cycle_vs_calculix(rec: dict) -> str:
    p = rec["params"]
    lines = head(rec, f"Cycle mode vs CalculiX on the same work: {p['part']} of final-cm, {p['fidelity']}")
    lines += [f"Same mesh, same N crank angles (the dynamics sampled at N angles), same output: the von Mises peak "
              "at each angle.  rigfem: assembly, one factorisation, the unit solves, stresses, superposition over "
              "the N angles, in process; CalculiX: the whole `ccx` process with the N angles as N *STEPs (one "
              f"factorisation each).  {p['threads']} thread each; median (min–max) of {p['repeats']} runs.  "
              "Nothing is extrapolated.", "",
              "| angles N | DOF | unit loads | rigfem s | CalculiX s | rigfem / CalculiX | largest peak difference |",
              "|---:|---:|---:|---:|---:|---:|---:|"]
    for n in p["angles"]:
        m = p[f"{n} angles"]
        diff = rec["summary"][f"ccx, {n} angles"]["max_peak_rel_diff"]["max"]
        lines.append(f"| {m['rows']} | {m['dof']:,} | {m['unit_loads']} | {rng(rec, f'rigfem, {n} angles')} | "
                     f"{rng(rec, f'ccx, {n} angles')} | **{rec['derived'][f'rigfem / ccx, {n} angles']:.3f}** | "
                     f"{diff:.1e} |")
    return "\n".join(lines) + "\n"


def calculix_vs_rigfem(rec: dict) -> str:
    p, d, m = rec["params"], rec["derived"], rec["params"]["mesh"]
    r = {k: med(rec, "rigfem", k) for k in rec["summary"]["rigfem"]}
    c = {k: med(rec, "ccx", k) for k in rec["summary"]["ccx"]}
    u = {k: med(rec, "unit cases", k) for k in rec["summary"]["unit cases"]}
    lines = head(rec, "rigfem vs CalculiX 2.20: 700 mm crank rail, curved P2")
    lines += [f"Case: {p['case']}  ", f"Mesh: {m['nodes']} nodes, {m['tets']} C3D10, **{m['dof']} DOF** "
              f"(size {m['size_mm']} mm, {m['refine_size_mm']} mm on {', '.join(m['refine'])})  ",
              f"Threads: {p['threads']} for both (rigfem solver: {p['rigfem_solver']}, backward error "
              f"{p['rigfem_backward_error']:.2g}; ccx: {p['ccx']}); median of {p['repeats']} repeats, each runs "
              "rigfem then ccx on the same exported deck."
              + (f"  Before timing, rigfem solves the rail once on a coarse mesh ({p['rigfem warm-up s']:.1f} s: "
                 "imports and the FE kernels, a one-time cost per process)." if "rigfem warm-up s" in p else ""),
              "", "| step | rigfem s | CalculiX s |", "|---|---:|---:|"]
    rows = [("mesh (gmsh)", r["mesh"], None), ("assembly (P2 mesh + stiffness)", r["assembly"], None),
            ("supports + loads", r["supports_loads"], None), ("factorise", r["factorise"], None),
            ("solve", r["solve"], None), ("stress recovery", r["stress"], None),
            ("**FE total** (same mesh given)", r["fe_total"], c["wall"]), ("total incl. meshing", r["total"], None),
            ("CPU time, FE total (user + system)", r["cpu_fe_total"], c["cpu"])]
    lines += [f"| {name} | {v:.2f} | {'' if w is None else f'{w:.2f}'} |" for name, v, w in rows]
    lines += ["", f"CalculiX wall time is the whole ccx process; ccx's own \"Total CalculiX Time\": "
              f"{c['ccx_reported']:.2f} s; deck export {c['export']:.2f} s (not counted).", "",
              f"FE wall time ratio rigfem / CalculiX: **{d['FE wall ratio rigfem / ccx']:.2f}**; including meshing "
              f"{d['wall ratio incl. meshing']:.2f}; CPU time ratio {d['CPU ratio']:.2f}.", "",
              f"**{p['unit cases']} unit load cases** on the same mesh ({p['unit load']}): rigfem (assembly + one "
              f"factorisation, {p['unit cases']} solves, stresses) {u['rigfem_fe']:.2f} s, CalculiX "
              f"({p['unit cases']} *STEPs) {u['ccx']:.2f} s, ratio **{d['unit cases wall ratio rigfem / ccx']:.2f}**;"
              f" largest peak difference {100 * rec['summary']['unit cases']['max_peak_rel_diff']['max']:.4f} %.", "",
              f"Agreement: peak von Mises {100 * d['peak von Mises rel diff']:.4f} %, tip displacement "
              f"{100 * d['tip displacement rel diff']:.4f} % (largest over the repeats)."]
    return "\n".join(lines) + "\n"


def le10_outliers(rec: dict) -> list[dict]:
    """The levels whose σyy(D) is more than 2 % off the reference."""
    return [r for r in rec["samples"]["levels"] if abs(r["error_pct"]) > 2.0]


def le10(rec: dict) -> str:
    lines = head(rec, "NAFEMS LE10, thick plate under pressure: rigfem vs CalculiX")
    lines += [f"σyy at D (2000, 0, 300) mm, target {LE10_TARGET} MPa (NAFEMS TNSB Rev. 3, 1990).  Quarter plate, "
              "curved P2 tetrahedra (C3D10 in ccx) on the identical mesh, supports and nodal loads "
              f"(`rigfem.verification.le10`); {rec['params']['threads']} thread per code.  Every mesh this command ran "
              "is listed.", "",
              "| h (mm) | layers | tets | DOF | rigfem σyy(D) (MPa) | error | ccx σyy(D) (MPa) | error | "
              "rigfem time (s) | ccx time (s) | time ratio rigfem/ccx | runs | rigfem peak RSS (MiB) | "
              "ccx peak RSS (MiB) | mesh time (s) |", "|" + "---|" * 15]
    for r in rec["samples"]["levels"]:
        h = f"{r['size_mm']:g}"
        t_r, t_c = med(rec, f"{h} mm rigfem"), med(rec, f"{h} mm ccx")
        lines.append(f"| {h} | {r['layers']} | {r['tets']} | {r['dof']} | {r['syy_D']:.4f} | {r['error_pct']:+.2f} % | "
                     f"{r['syy_D_ccx']:.4f} | {r['error_ccx_pct']:+.2f} % | {t_r:.2f} | {t_c:.2f} | {t_r / t_c:.2f} | "
                     f"{r['runs']} | {r['rigfem_rss_mib']:.0f} | {r['ccx_rss_mib']:.0f} | {r['mesh_s']:.2f} |")
    lines += ["", "Points outside ±2 %:" if le10_outliers(rec) else "Every point is within ±2 %."]
    lines += [f"- h = {r['size_mm']:g} mm ({r['dof']:,} DOF): {r['error_pct']:+.2f} %: {le10_reason(r)}"
              for r in le10_outliers(rec)]
    lines += ["", "Times are wall-clock medians of the runs column.  rigfem: model, assembly, factorisation, solve, "
              "stress recovery, in-process; ccx: the whole `ccx` process.  Peak RSS: VmHWM of the solving "
              "subprocess (rigfem, with the interpreter and numpy/scipy/MKL baseline of about "
              f"{rec['samples']['levels'][0]['rigfem_rss_base_mib']:.0f} MiB) and of its ccx children."]
    return "\n".join(lines) + "\n"


def le10_reason(r: dict) -> str:
    """Why a level misses 2 %: a coarse mesh, when CalculiX on the same mesh misses it alike."""
    same = abs(r["error_ccx_pct"] - r["error_pct"]) < 0.01
    return (f"a coarse mesh, {r['layers']} element layers through the 600 mm thickness and {r['size_mm']:g} mm "
            f"elements at the stress raiser D; CalculiX on the same mesh reads {r['error_ccx_pct']:+.2f} %"
            + (", so it is discretisation error, not a solver fault" if same else ": the codes differ here") + ".")


def stages(rec: dict) -> str:
    p = rec["params"]
    cols = list(rec["samples"])
    stage_names = [k for k in rec["samples"][cols[0]][0] if k != "total (profiled)"]
    stage_names += [k for c in cols for k in rec["samples"][c][0] if k not in stage_names and k != "total (profiled)"]
    lines = head(rec, "Where the time goes, per stage")
    lines += [f"`rigfem check final-cm --fidelity {p['fidelity']}`: cold = empty rigfem and numba caches, warm = "
              "the caches filled; cumulative seconds per stage under cProfile (one process each).  The pictures "
              "are the functions the check calls.", "",
              "| stage | " + " | ".join(cols) + " |", "|---|" + "---:|" * len(cols)]
    for st in stage_names:
        vals = [rec["samples"][c][0].get(st) for c in cols]
        lines.append(f"| {st} | " + " | ".join(f"{v:.2f}" if v else "–" for v in vals) + " |")
    lines.append("| **total (profiled)** | " + " | ".join(f"**{rec['samples'][c][0]['total (profiled)']:.1f}**"
                                                       for c in cols) + " |")
    return "\n".join(lines) + "\n"


#: profile_timeline's name of the time from its probe's start to the command's first stage event
BEFORE_FIRST_STAGE = "before the first stage: imports, arguments, the command's first work"


def timeline_group(stage: str) -> str:
    """A stage's group in the timeline tables: the per-part, per-chunk and per-candidate stages as one."""
    import re

    if stage.startswith("solving part"):
        return "FE: mesh, solve and refine each part"
    if stage.startswith("configurations, chunk") or stage.startswith("configurations,"):
        return "configurations (chunks on Dask)"
    if stage.startswith("stress verdict"):
        return "stress verdicts of the candidates"
    if stage.startswith("unit solutions"):
        return "unit solutions"
    if stage in ("imports (rigfem.cli)", "start (Python up)"):  # the probe's first records' names for these two
        return {"start (Python up)": "start", "imports (rigfem.cli)": BEFORE_FIRST_STAGE}[stage]
    return re.sub(r"\s*\(.*\)$", "", stage)


def timeline_rows(rec: dict) -> list[str]:
    """Per command of the record (benchmarks/profile_timeline.py): wall time, peak tree RSS, and its
    stage groups in seconds (share of the wall time) and peak RSS, in the order they first ran."""
    out = ["| command | wall | peak RSS | where the time goes (seconds, share, peak tree RSS) |", "|---|---:|---:|---|"]
    for series, rows in rec["samples"].items():
        r, groups = rows[0], {}
        for st in r["stages"]:
            g = groups.setdefault(timeline_group(st["stage"]), [0.0, 0.0])
            g[0] += st["seconds"]
            g[1] = max(g[1], st["peak_tree_rss_mib"])
        cells = "; ".join(f"{name} {t:.1f} s ({100 * t / r['wall_s']:.0f} %, {m:.0f} MiB)"
                          for name, (t, m) in groups.items() if t >= 0.05)
        out.append(f"| {series} | {r['wall_s']:.1f} s | {r['peak_tree_rss_mib']:.0f} MiB | {cells} |")
    return out


def timeline_note(rec: dict) -> str:
    """When and at which commit each series was measured ("before: ..." series: the baseline's code)."""
    by: dict[str, list[str]] = {}
    for series, p in rec["params"].get("provenance", {}).items():
        by.setdefault(f"{p['date'][:16].replace('T', ' ')} UTC at commit {p['commit'][:10]}"
                      f"{' (dirty)' if p.get('dirty') else ''}", []).append(series)
    return "Measured " + "; ".join(f"{w}: {', '.join(s)}" for w, s in by.items()) + "." if by else ""


def timeline(rec: dict) -> str:
    lines = head(rec, "Where a command's time and memory go: its stages on a clock")
    lines += ["Each command as a user runs it (`python -m rigfem ...`, its own progress observer), every stage "
              "event time-stamped; a stage lasts until the next begins (what runs inside it in parallel shows as "
              "its width, not as a sum); peak RSS: the whole process tree (mesher, solver and picture children "
              "included) while the stage ran.  Cold: empty rigfem and numba caches; warm: the caches the cold run "
              "filled.", "", *timeline_rows(rec), "", timeline_note(rec), ""]
    for series, rows in rec["samples"].items():
        r = rows[0]
        lines += [f"## {series}: {r['wall_s']:.1f} s, peak {r['peak_tree_rss_mib']:.0f} MiB", "",
                  "| stage | starts at | seconds | share | peak tree RSS |", "|---|---:|---:|---:|---:|"]
        lines += [f"| {st['stage']} | {st['start_s']:.1f} s | {st['seconds']:.2f} | "
                  f"{100 * st['seconds'] / r['wall_s']:.0f} % | {st['peak_tree_rss_mib']:.0f} MiB |"
                  for st in r["stages"]]
        lines.append("")
    return "\n".join(lines)


def kinematics(rec: dict) -> str:
    p = rec["params"]
    lines = head(rec, "Closed-form kinematics benchmark")
    lines += [f"Four-bar {'/'.join(f'{v:g}' for v in p['four-bar mm'])} mm, {p['angles']} crank angles over a full "
              f"turn; median of {p['runs']} runs in process after one warm-up.", "", "| step | median (ms) |",
              "|---|---|"]
    lines += [f"| {k} | {med(rec, k, 'ms'):.3f} |" for k in rec["samples"]]
    lines += [f"| **total** | **{rec['derived']['total ms']:.3f}** (target < {p['target_ms']:g}) |"]
    return "\n".join(lines) + "\n"


def dynamics(rec: dict) -> str:
    lines = head(rec, "Linkage dynamics timing (rig four-bar b2=540 b3=840 b4=780 d=1020 mm)")
    lines += ["Median of repeats after one warm-up, all cases in one run.  The closed form is what `simulate` "
              "uses for a toggle-free rig four-bar or slider-crank; the general solver is the reference it is "
              "tested against (tests/test_dynamics_closed.py).", "",
              "| case | wall median (ms) | wall min (ms) | CPU median (ms) | repeats |", "|---|---:|---:|---:|---:|"]
    for k, v in rec["summary"].items():
        if "wall_ms" in v:
            lines.append(f"| {k} | {v['wall_ms']['median']:.1f} | {v['wall_ms']['min']:.1f} | "
                         f"{v['cpu_ms']['median']:.1f} | {v['wall_ms']['n']} |")
    lines += ["", f"Closed form vs general solver at 5000 angles: "
              f"{rec['derived']['general / closed form, 5000 angles']:.1f}× faster (wall medians).  Peak RSS of "
              f"the benchmark process: {med(rec, 'benchmark process', 'peak_rss_mib'):.0f} MiB."]
    return "\n".join(lines) + "\n"


def fe_assembly(rec: dict) -> str:
    d, p = rec["derived"], rec["params"]
    lines = head(rec, "FE core benchmark")
    lines += [f"{d['case']}; medians of {p['reps']} runs (SuperLU and AMG: one run; AMG: CG to 1e-10, at most "
              f"{p['amg_maxiter']} iterations).  Rail = the P2 bar fixed at x = 0; cube = 100 mm P2 cube fixed "
              "on one face.", "", "| assembly of K | time [s] |", "|---|---|",
              f"| rigfem numba kernel | {d['assembly_rigfem_s']:.3f} |",
              f"| scikit-fem generic `asm(linear_elasticity)` | {d['assembly_skfem_asm_s']:.3f} (+ Basis "
              f"{d['assembly_skfem_basis_s']:.3f}) |", f"| speed-up | {d['assembly_speedup']:.1f}x |", "",
              "| part / solver | DOF | factorise/setup [s] | first solve [s] | 6 further cases [s] | 6 cases / first | "
              "rel. residual | backward error |", "|---|---|---|---|---|---|---|---|"]
    for m, r in d["solvers"].items():
        if "failed" in r:
            lines.append(f"| {m} | {r['dof']} | {r['factorise_s']:.2f} | failed: {r['failed'][:60]}… | | | | |")
            continue
        it = f" ({r['cg_iterations_6']} CG its)" if r["cg_iterations_6"] else ""
        lines.append(f"| {m} | {r['dof']} | {r['factorise_s']:.2f} | {r['first_solve_s']:.3f} | "
                     f"{r['block6_solve_s']:.3f}{it} | {100 * r['block6_over_first']:.0f} % | {r['residual']:.1e} | "
                     f"{r['backward_error']:.1e} |")
    lines += ["", f"Nodal stress recovery for 6 cases: {d['stress_recovery_6_cases_s']:.3f} s.  numba first call "
              f"(compile or cache load): {d['numba_first_call_s']:.2f} s."]
    return "\n".join(lines) + "\n"


def malloc_trim(rec: dict) -> str:
    p = rec["params"]
    lines = head(rec, "Dask's MALLOC_TRIM_THRESHOLD_ and the sweep's superposition")
    first = next(iter(rec["samples"].values()))[0]
    lines += [f"One sweep chunk of {first['configurations']} configurations, draft, single-threaded fresh "
              f"processes, median of {p['repeats']} each.", "",
              "| environment | wall s | user s | system s | minor page faults |", "|---|---:|---:|---:|---:|"]
    for k in rec["samples"]:
        lines.append(f"| {k} | {med(rec, k):.1f} | {med(rec, k, 'user_s'):.1f} | {med(rec, k, 'sys_s'):.1f} | "
                     f"{med(rec, k, 'minor_faults'):,.0f} |")
    lines += ["", f"With the variable the chunk takes {100 * rec['derived']['wall with / without - 1']:+.0f} % wall "
              "time; local sweep workers are started without it (`rigfem.sweep.run`)."]
    return "\n".join(lines) + "\n"


def bad_inputs(rec: dict) -> str:
    lines = head(rec, "Issue 24's and 38's examples: what rigfem prints and how long it takes")
    lines += ["Each example is its own process in an empty folder with an empty cache; the time is the wall "
              "time of the process (Ctrl-C: from the signal to its end), the memory the peak RSS of its "
              "process tree where measured.", "",
              "| example | command | exit | time (s) | peak MiB | files left | what rigfem prints (last line on stderr, else first on stdout) |",
              "|---|---|---:|---:|---:|---|---|"]
    for name, (r,) in rec["samples"].items():
        name, cmd, msg = (t.replace("|", r"\|") for t in (name, r["command"], r["prints"]))
        left = ", ".join(r["files_left"]) or "none"
        mib = f"{r['peak_tree_rss_mib']:.0f}" if r.get("peak_tree_rss_mib") is not None else "-"
        lines.append(f"| {name} | `{cmd}` | {r['exit']} | {r['wall_s']:.2f} | {mib} | {left} | {msg} |")
    lines += ["", f"Slowest to fail: {rec['derived']['slowest_s']:.1f} s."]
    return "\n".join(lines) + "\n"


#: record name -> its table renderer (results/benchmarks/<name>.md)
def perf_rows(rec: dict) -> list[str]:
    """Issue 41's table: row, goal, cold, warm, peak RSS, met (benchmarks/bench_perf.py's goals); where
    the record has a baseline's series (``--baseline``), each figure reads "before → after"."""
    from bench_perf import status  # the one home of the goals (loads no FE code)

    def t(s: float | None) -> str:  # a tenth of a second under 100 s: a row near its goal reads so
        return "-" if s is None else hms(s) if s >= 100 else f"{s:.1f} s" if s >= 10 else f"{s:.2f} s"

    before = {v["row"]: v for v in status(rec, "before: ")}

    def fig(v: dict, key: str, fmt) -> str:
        b = before[v["row"]].get(key)
        return ("-" if v.get(key) is None else fmt(v[key])) if b is None else f"{fmt(b)} → {fmt(v.get(key))}"

    def mib(x: float | None) -> str:
        return "-" if x is None else f"{x:.0f} MiB"

    out = ["| work | goal | cold | warm | peak RSS | |", "|---|---|---:|---:|---:|---|"]
    for v in status(rec):
        cells = [fig(v, "rss_mib", mib) if v["rss_mib"] is not None else "",
                 f"folder {fig(v, 'folder_mb', lambda x: f'{x:.1f} MB')}" if "folder_mb" in v else "",
                 f"ratio {fig(v, 'ratio', lambda x: f'{x:.2f}')}" if "ratio" in v else "",
                 f"up to {v['dof']:,.0f} DOF, {rec['derived']['dof MiB per 1000 DOF']:.1f} MiB per 1000 DOF, "
                 f"R² {v['r2']:.3f}" if "dof" in v else ""]
        met = {None: "not measured", True: "met", False: "**not met**"}[v["met"]]
        out.append(f"| {v['work']} | {v['goal']} | {fig(v, 'cold_s', t)} | {fig(v, 'warm_s', t)} | "
                   f"{'; '.join(c for c in cells if c) or '-'} | {met} |")
    return out


def perf_note(rec: dict) -> str:
    """When and where each row was measured (rows are kept until re-measured)."""
    by = {}
    for series, p in rec["params"]["provenance"].items():
        by.setdefault(f"{p['date'][:10]} at commit {p['commit'][:10]}{' (dirty)' if p.get('dirty') else ''}",
                      []).append(series)
    base = rec["params"].get("baseline")
    return ("Medians of separate processes (cold: empty rigfem and numba caches; warm: the caches the last cold run "
            "filled); peak RSS: the largest of the row's cold runs, whole process tree"
            + (f"; before → after: the code of {base['baseline']} ({base['commit'][:10]}) and of this commit, "
               "measured interleaved in one run" if base else "")
            + (f"; calibration (SuperLU of a 24³ 3-D Laplacian, 1 thread, before every row) median "
               f"{rec['derived']['calibration median s']:.2f} s" if "calibration median s" in rec["derived"] else "")
            + ".  Measured "
            + "; ".join(f"{w}: {', '.join(s)}" for w, s in by.items()) + f" on {rec['machine']['cores']} shared "
            "cores — results/benchmarks/perf.md.")


def _sides(rec: dict, series: str, key: str, text) -> str:
    """``text(sample)`` of the first run of the baseline's ``series`` and of this commit's, where they hold ``key``."""
    out = [f"{side}: {text(x)}" for side, name in (("before", f"before: {series}"), ("after", series))
           if key in (x := (rec["samples"].get(name) or [{}])[0])]
    return "; ".join(out)


def profiles(rec: dict) -> list[str]:
    """The profiles of the folder row (bytes by kind) and of the CalculiX row (rigfem's FE by step)."""
    kinds = {"vtu_critical": "VTU at the critical angles", "vtu_frames": "VTU animation frames", "png": "PNG",
             "html": "HTML", "json": "JSON", "md": "Markdown", "pvd": "PVD", "other": "other"}
    steps = {"assembly": "assembly", "supports_loads": "supports and loads", "factorise": "factorisation",
             "solve": "solve", "stress": "stress recovery"}
    folder = _sides(rec, "check standard cold", "folder_kinds_mb", lambda x: ", ".join(
        f"{kinds[k]} {v:.1f} MB" for k, v in x["folder_kinds_mb"].items() if v >= 0.05) + f" of {x['folder_mb']:.1f} MB")
    ccx = _sides(rec, "ccx", "rigfem_steps_s", lambda x: ", ".join(
        f"{n} {x['rigfem_steps_s'][k]:.2f} s" for k, n in steps.items())
        + f" of rigfem's {x['rigfem_steps_s']['fe_total']:.2f} s; CalculiX {x['ccx_s']:.2f} s")
    return ([f"The result folder by kind: {folder}."] if folder else []) + \
        ([f"The CalculiX row, rigfem's FE by step (one run, the same mesh): {ccx}."] if ccx else [])


def perf(rec: dict) -> str:
    lines = head(rec, "Performance goals of issue 41: every row cold and warm, separate processes")
    lines += perf_rows(rec) + ["", perf_note(rec), *(x for p in profiles(rec) for x in ("", p)),
                               "", "| series | runs | wall s | peak tree RSS MiB | "
                                                      "load average at the starts |", "|---|---:|---:|---:|---|"]
    for s, rows in rec["samples"].items():
        loads = ", ".join(f"{x['load_before'][0]:.1f}" for x in rows if "load_before" in x)
        wall = rng(rec, s, "seconds" if s == "calibration" else "wall_s", ".2f")
        rss = "-" if s == "calibration" else rng(rec, s, "peak_tree_rss_mib", ".0f")
        lines.append(f"| {s} | {len(rows)} | {wall} | {rss} | {loads} |")
    return "\n".join(lines) + "\n"


def adaptive(rec: dict) -> str:
    """Fixed preset meshes against the verdict-driven ladder, per part case."""
    p = rec["params"]
    lines = head(rec, f"`rigfem check {p['scene']}`: fixed preset mesh (before) vs verdict-driven ladder (after)")
    lines += ["Each check a separate cold process (empty caches).  Seconds: the part's mesh, assembly and solves "
              "(every level tried, after; shared by its two modes).  Band: peak · error_pct, MPa.  Consistent: same "
              "verdict and |after − before| ≤ the sum of both bands.", "",
              "| preset | part | mode | DOF before → after (ladder total) | level, why | s before → after | "
              "peak ± band before, MPa | after, MPa | verdict | consistent |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rec["samples"]["parts"]:
        lines.append(f"| {r['fidelity']} | {r['part']} | {r['mode']} | {r['before_dofs']} → {r['after_dofs']} "
                     f"({r['after_ladder_dofs']}) | {r['after_level']}, {r['after_stopped']} | {r['before_s']:.1f} → "
                     f"{r['after_s']:.1f} | {r['before_peak_mpa']:.2f} ± {r['before_band_mpa']:.2f} | "
                     f"{r['after_peak_mpa']:.2f} ± {r['after_band_mpa']:.2f} | {r['before_verdict']} → "
                     f"{r['after_verdict']} | {'yes' if r['consistent'] else '**no**'} |")
    if rec["samples"].get("committed"):
        lines += ["", f"Against the committed report (results/{p['scene']}/report.json):", "",
                  "| part | mode | committed MPa | after MPa | difference MPa | both bands MPa | consistent |",
                  "|---|---|---|---|---|---|---|"]
        lines += [f"| {r['part']} | {r['mode']} | {r['committed_peak_mpa']:.2f} | {r['after_peak_mpa']:.2f} | "
                  f"{r['difference_mpa']:+.2f} | {r['bands_mpa']:.2f} | {'yes' if r['consistent'] else '**no**'} |"
                  for r in rec["samples"]["committed"]]
    lines += ["", "| preset | wall s before → after | peak tree RSS MiB before → after |", "|---|---|---|"]
    lines += [f"| {f} | {med(rec, f + ' before'):.1f} → {med(rec, f + ' after'):.1f} | "
              f"{med(rec, f + ' before', 'peak_tree_rss_mib'):.0f} → {med(rec, f + ' after', 'peak_tree_rss_mib'):.0f} |"
              for f in p["fidelity"]]
    lines += [""] + [f"{k}: {v:.2f}" + "  " for k, v in rec["derived"].items()]
    return "\n".join(lines) + "\n"


def levers(rec: dict) -> str:
    lines = head(rec, f"Issue 26's other levers: `rigfem check {rec['params']['scene']}` "
                      f"({rec['params']['fidelity']}) before and after")
    lines += ["One process per run (benchmarks/bench_levers.py): cold = fresh rigfem and numba caches, warm = "
              "the caches it filled.  Peak memory: the peak RSS of the check's process tree.", "",
              "| run | wall s | peak tree RSS MiB | load average at the start | source |", "|---|---:|---:|---:|---|"]
    runs = rec["params"]["runs"]
    for series, rows in rec["samples"].items():
        label = series.split(" ", 1)[0]
        lines.append(f"| {series} | {rows[0]['wall_s']:.1f} | {rows[0]['peak_tree_rss_mib']:.0f} | "
                     f"{rows[0]['load_before'][0]:.1f} | {runs.get(label, {}).get('source', '')} |")
    for label, change in rec["derived"].get("peak change vs before", {}).items():
        lines += ["", f"Peak change {label} vs before (relative):", ""]
        lines += [f"- {k}: {v:.2e}" for k, v in sorted(change.items())]
    return "\n".join(lines) + "\n"


def pardiso(rec: dict) -> str:
    p, d = rec["params"], rec["derived"]
    lines = head(rec, "MKL PARDISO's defaults against rigfem's settings on a rail's stiffness")
    first = next(iter(rec["samples"].values()))[0]
    lines += [f"{p['part']}, {p['mode']}, {p['level']} level: {first['dofs']:,} DOF; one solve of {p['rhs']} "
              f"right-hand sides; fresh processes alternating the settings, median of {p['repeats']} each.", "",
              "| settings | analysis s | factorise s | solve s | refinement steps in the solve | "
              "peak memory growth over the three phases (MiB) |", "|---|---:|---:|---:|---:|---:|"]
    for k in rec["samples"]:
        lines.append(f"| {k} | {med(rec, k, 'analysis_s'):.2f} | {med(rec, k, 'factorise_s'):.2f} | "
                     f"{med(rec, k, 'solve_s'):.2f} | {med(rec, k, 'refinement_steps'):.0f} | "
                     f"{med(rec, k, 'peak_rss_growth_kib') / 1024:.0f} |")
    for other, what in (("MKL", "MKL's defaults"), ("without blocks", "Without the variable blocks")):
        lines += ["", f"{what} / rigfem's: analysis {d[f'analysis_s {other} / rigfem']:.2f}×, factorise "
                  f"{d[f'factorise_s {other} / rigfem']:.2f}×, solve {d[f'solve_s {other} / rigfem']:.2f}×, "
                  f"memory {d[f'peak_rss_growth_kib {other} / rigfem']:.2f}×."]
    lines += ["", f"Worst relative residual {d['residual_max']:.1e}.  rigfem checks every solve's backward error "
              "and refines only where it is needed (`rigfem.fe.solver.LinearSolver.solve`)."]
    return "\n".join(lines) + "\n"


def mesh(rec: dict) -> str:
    p, d = rec["params"], rec["derived"]
    old, new = p["precision"]
    lines = head(rec, f"gmsh's meshing steps per part and ladder level ({p['scene']}, {p['fidelity']}): "
                      "gmsh's default 1D integration precision against rigfem's")
    lines += [f"Mesh.LcIntegrationPrecision: gmsh's default {p['precision'][old]:g}, rigfem's {p['precision'][new]:g}.  "
              "The check's own meshes (its cases' loaded holes refined), no cache, one thread; all meshes of a "
              f"setting in one fresh process, the settings alternating, median of {p['repeats']} processes each.  "
              "Seconds per step from the mesher (`meta[\"stages\"]`; second order includes gmsh's "
              "HighOrderElastic smoothing of the rails).", "",
              "| part | level | tets (gmsh → rigfem) | min SICN | 1D s | 2D s | 3D s | second order s | total s |",
              "|---|---|---|---|---:|---:|---:|---:|---:|"]
    for m in p["meshes"]:
        a, b = f"{old}: {m}", f"{new}: {m}"
        part, level = m.rsplit(" ", 1)
        lines.append(f"| {part} | {level} | {med(rec, a, 'tets'):.0f} → {med(rec, b, 'tets'):.0f} | "
                     f"{med(rec, a, 'min_sicn'):.3f} → {med(rec, b, 'min_sicn'):.3f} | "
                     + " | ".join(f"{med(rec, a, k):.2f} → {med(rec, b, k):.2f}"
                                  for k in ("1D", "2D", "3D", "second order", "seconds")) + " |")
    lines += ["", f"All meshes: {d['seconds, all meshes: gmsh / rigfem']:.2f}× the time at gmsh's default "
              f"(the 1D step {d['1D seconds, all meshes: gmsh / rigfem']:.1f}×); the largest change of a mesh's "
              f"tet count {100 * d['largest tet count change']:.2f} %."]
    return "\n".join(lines) + "\n"


def cache_rows(rec: dict) -> list[str]:
    """Per cache kind: its workload, the warm run with every kind and without this one (medians, s),
    and its disk after the cold runs."""
    d = rec["derived"]["kinds"]
    out = ["| kind | workload | warm, every kind kept (s) | warm, this kind not kept (s) | saved (s) | disk |",
           "|---|---|---|---|---|---|"]
    for kind, k in d.items():
        series = f"{k['workload']} warm without {kind}"
        b = k["disk_bytes"]
        size = f"{b / 1e9:.2f} GB" if b >= 1e9 else f"{b / 1e6:.1f} MB" if b >= 1e5 else f"{b / 1e3:.1f} kB"
        out.append(f"| {kind} | {k['workload']} | {rng(rec, k['workload'] + ' warm')} | {rng(rec, series)} | "
                   f"{k['saved_s']:.1f} | {size} |")
    return out


def cache_note(rec: dict) -> str:
    def spread(workload: str) -> float:
        w = rec["summary"][f"{workload} warm"]["wall_s"]
        return w["max"] - w["min"]

    lo, hi = (rec["summary"]["check warm"]["wall_s"][x] for x in ("min", "max"))
    kinds = rec["derived"]["kinds"]
    pay = [k for k, v in kinds.items() if v["saved_s"] > spread(v["workload"])]
    rest = [k for k in kinds if k not in pay]
    return (f"Measured at {rec['commit']['sha'][:10]}{' (dirty)' if rec['commit']['dirty'] else ''}, "
            f"{rec['date'][:10]}, load average {rec['load'][0]:.1f}: the warm checks spread {lo:.1f}-{hi:.1f} s. "
            f"Saving more than its workload's warm spread: {', '.join(pay)}; "
            f"no saving measurable at this load: {', '.join(rest)} (to be measured on an idle machine "
            "before any is dropped).")


def same_results(rec: dict) -> str:
    """The reference scenes' figures with the baseline's code and this commit's (bench_same_results.py)."""
    p, d = rec["params"], rec["derived"]
    lines = head(rec, f"The reference scenes' verdicts and peaks: the code of {p['baseline']['rev']} and of this commit")
    lines += [f"Each scene checked as tests/test_reference_scenes.py checks it, {p['repeats']} times per side, each "
              f"run its own process with empty caches and {p['threads']} MKL/OpenMP thread; the first run of each "
              "side compared with the other side's, and with the side's own repeats (run to run).  Largest "
              "relative difference over the scene's part cases; same: verdict, mesh level, FE nodes and tets of "
              "every part case.", "",
              "| scene | part cases | peak | error estimate | utilisation | largest displacement | crank angle of "
              "the peak | same verdicts and meshes | bit for bit the same | peak, run to run (before; after) |",
              "|---|---:|---:|---:|---:|---:|---:|---|---|---|"]

    def runs(x: list) -> str:
        return ", ".join(f"{c['rel']['peak_mpa']:.1e}" for c in x) or "-"

    for scene, (r,) in rec["samples"].items():
        c = r["before -> after"]
        same = "yes" if not c["different"] and not c["missing"] else "**no**: " + "; ".join(c["different"] + c["missing"])
        lines.append(f"| {scene} | {len(c['cases'])} | {c['rel']['peak_mpa']:.1e} | {c['rel']['error_pct']:.1e} | "
                     f"{c['rel']['utilisation_pct']:.1e} | {c['rel']['max_displacement_mm']:.1e} | "
                     f"{c['rel']['crank_deg']:.1e} | {same} | {(', '.join(c['bit for bit']) or 'none') if 'bit for bit' in c else '-'} | "
                     f"{runs(r['before, run to run'])}; "
                     f"{runs(r['after, run to run'])} |")
    lines += ["", f"Largest peak difference, before → after: {d['largest peak difference before -> after']:.1e}; run "
              f"to run: {d['largest peak difference run to run'] or 0:.1e}; verdicts and meshes the same: "
              f"{'yes' if d['verdicts and meshes the same'] else '**no**'} ({d['part cases compared']} part cases)."]
    return "\n".join(lines) + "\n"


def cache_kinds(rec: dict) -> str:
    return (f"# What each kind of cache entry saves\n\nCommand: `{rec['command']}`\n\n"
            + "\n".join(cache_rows(rec)) + "\n\n" + cache_note(rec) + "\n")


RENDER: dict[str, Callable[[dict], str]] = {
    "check": check, "sweep": sweep, "sweep_grid_cost": sweep_grid_cost, "cycle_vs_calculix": cycle_vs_calculix,
    "calculix_vs_rigfem": calculix_vs_rigfem, "le10": le10, "stages": stages, "kinematics": kinematics,
    "dynamics": dynamics, "fe_assembly": fe_assembly, "malloc_trim": malloc_trim, "perf": perf,
    "bad_inputs": bad_inputs, "adaptive": adaptive,
    "levers": levers, "pardiso": pardiso, "mesh": mesh, "cache_kinds": cache_kinds, "timeline": timeline,
    "same_results": same_results}
