"""Issue 41's performance table in one command: every row cold and warm, each run a separate process.

    python benchmarks/bench_perf.py                      # every row (long: the sweep, --rig, 1M DOF)
    python benchmarks/bench_perf.py --rows check synth sweep ccx --baseline 450ffeb   # before/after, one run
    python benchmarks/bench_perf.py --rows light check --repeats 1 --fidelity draft
    python benchmarks/bench_perf.py --goals              # measure nothing: the record against the goals

Each run is its own process (benchmarks/record.timed_process: wall time, peak RSS of its whole
process tree, load average) running this checkout's code (``PYTHONPATH``: an editable install of
another tree is not what runs).  *Cold*: empty rigfem and numba caches; *warm*: the caches the
last cold run filled.  ``--baseline REV`` runs every chosen row of issue 41 also with the code of
REV (a temporary git worktree), interleaved row by row with this checkout's, so that both sides
see the same machine and load; its series are named ``before: <series>``.  Before every row a
calibration (a fixed sparse factorisation, 1 thread, its own process) is timed, so that a slower
or busier machine shows in the record instead of hiding a regression.  Writes
results/benchmarks/perf.json (rows measured before and not re-measured are kept, each series with
the date, commit and dirty flag it was measured at); ``python benchmarks/publish.py`` writes
perf.md and README's Performance table, each row met / not met against :data:`GOALS`.
"""

from __future__ import annotations

import argparse
import compileall
import contextlib
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_folder_size import measure
from record import OUT, ROOT, cold_env, commit, timed_process, write_record

MIB = 2**20
#: the one home of the goals (issue 41; the light and DOF rows are issue 26's): row -> the work, the
#: goal as written, the limits it sets (cold_s / warm_s: median wall time; rss_mib: peak tree RSS of
#: every cold run; folder_mb: the result folder of the cold runs, MB = 10^6 bytes; ratio: rigfem/ccx;
#: dof: the largest DOF measured, r2: the linear fit's R²)
GOALS: dict[str, dict] = {
    "check standard": {"work": "`rigfem check final-cm --force`, standard", "goal": "cold < 15 s, < 1 GB; warm < 1 s",
                       "cold_s": 15.0, "warm_s": 1.0, "rss_mib": 1024.0},
    "check draft": {"work": "`rigfem check final-cm --force --fidelity draft`", "goal": "cold < 10 s", "cold_s": 10.0},
    "folder": {"work": "result folder of a standard check (final-cm)", "goal": "< 15 MB, the same information",
               "folder_mb": 15.0},
    "synthesize --rig": {"work": "`rigfem synthesize motion --points 0,0 -15.12,-9 -29.128,-4 --rig --top 3`",
                         "goal": "cold < 30 s, < 1.5 GB", "cold_s": 30.0, "rss_mib": 1536.0},
    "sweep": {"work": "`rigfem sweep --four-bar` (2 workers), end to end", "goal": "cold < 90 s, warm < 5 s",
              "cold_s": 90.0, "warm_s": 5.0},
    "ccx": {"work": "one part's FE vs CalculiX on the same mesh (700 mm rail, P2, 1 thread each)",
            "goal": "FE wall ratio rigfem/ccx ≤ 0.3", "ratio": 0.3},
    "help": {"work": "`rigfem --help`", "goal": "< 0.3 s (issue 26)", "cold_s": 0.3, "warm_s": 0.3},
    "version": {"work": "`rigfem --version`", "goal": "< 0.3 s (issue 26)", "cold_s": 0.3, "warm_s": 0.3},
    "parts": {"work": "`rigfem parts`", "goal": "< 0.3 s (issue 26)", "cold_s": 0.3, "warm_s": 0.3},
    "kinematics": {"work": "`rigfem kinematics mech2-fourbar-coupler-point`", "goal": "< 0.3 s (issue 26)",
                   "cold_s": 0.3, "warm_s": 0.3},
    "dof": {"work": "peak RSS against DOF (P2 bar 700 × 23 × 24 mm, factorise and solve)",
            "goal": "linear, up to 1M DOF or the largest mesh the machine takes (issue 26)", "dof": 1e6, "r2": 0.98},
}
#: the series a row's figures come from, where its name is not the row's
SERIES = {"folder": "check standard cold"}
#: the README command of each light row (argv after ``rigfem``)
LIGHT = {"help": ["--help"], "version": ["--version"], "parts": ["parts"],
         "kinematics": ["kinematics", "mech2-fourbar-coupler-point"]}
SYNTH = ["synthesize", "motion", "--points", "0,0", "-15.12,-9", "-29.128,-4", "--rig", "--top", "3"]
#: bar divisions along its length for the DOF row: 726·nx + 363 DOF (P2, 5 × 5 divisions across)
DOF_NX = (35, 70, 140, 280, 560, 1100, 1378)
ROWS = ("check", "light", "synth", "sweep", "ccx", "dof")
#: the rows of issue 41's table (the ones ``--baseline`` measures twice)
COMPARED = ("check", "synth", "sweep", "ccx")
ONE_THREAD = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
#: the calibration: LU of a 7-point 3-D Laplacian (24³ unknowns, about a second) by SciPy's SuperLU, 1 thread
CALIBRATION = """
import time, numpy as np, scipy.sparse as sp, scipy.sparse.linalg as sl
n = 24
d = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n))
i = sp.identity(n)
a = (sp.kron(sp.kron(d, i), i) + sp.kron(sp.kron(i, d), i) + sp.kron(sp.kron(i, i), d)).tocsc()
t = time.perf_counter()
sl.splu(a, permc_spec="COLAMD").solve(np.ones(n ** 3))
print(time.perf_counter() - t)
"""


def _sample(r: dict) -> dict:
    """A run's sample without its output text (kept: wall, peak tree RSS, exit, load averages)."""
    return {k: v for k, v in r.items() if not k.endswith("_tail")}


def env_of(tmp: str | Path, tree: Path, **extra: str) -> dict:
    """A cold run's environment (benchmarks/record.cold_env) running the code of ``tree``: its
    PYTHONPATH (its benchmarks/ too, for its scripts' sibling imports), and no current folder on the
    path (``python -m`` would put it first)."""
    return cold_env(tmp, PYTHONPATH=os.pathsep.join((str(tree), str(tree / "benchmarks"))), PYTHONSAFEPATH="1",
                    **extra)


def runs_code_of(tree: Path) -> None:
    """Refuse to measure if ``python -m rigfem`` in :func:`env_of` would not import ``tree``'s rigfem."""
    with tempfile.TemporaryDirectory(prefix="perf-") as tmp:
        r = subprocess.run([sys.executable, "-c", "import rigfem; print(rigfem.__file__)"], env=env_of(tmp, tree),
                           capture_output=True, text=True, check=True)
    if not Path(r.stdout.strip()).resolve().is_relative_to(tree.resolve()):
        raise SystemExit(f"the runs would import {r.stdout.strip()}, not the code of {tree}")


def _rigfem(args: list[str], env: dict, ok: tuple[int, ...] = (0,)) -> dict:
    """One ``python -m rigfem ARGS`` process; refuses an unexpected exit code."""
    r = timed_process([sys.executable, "-m", "rigfem", *args], env=env)
    if r["exit"] not in ok:
        raise SystemExit(f"rigfem {' '.join(args)} exited {r['exit']}: {r['stderr_tail']}")
    return _sample(r)


def cold_warm(run, tree: Path, repeats: int, warm: bool = True) -> tuple[list, list]:
    """``repeats`` cold runs, each on fresh caches of its own; then ``repeats`` warm runs on the
    caches the last cold run filled (``warm=False``: none)."""
    cold, hot = [], []
    with contextlib.ExitStack() as stack:
        for _ in range(repeats):
            tmp = stack.enter_context(tempfile.TemporaryDirectory(prefix="perf-"))
            cold.append(run(env_of(tmp, tree), tmp))
        hot = [run(env_of(tmp, tree), tmp) for _ in range(repeats if warm else 0)]
    return cold, hot


#: the result folder's parts (benchmarks/bench_folder_size.measure), its profile
FOLDER_KINDS = ("vtu_critical", "vtu_frames", "png", "html", "json", "md", "pvd", "other")


def _check(fidelity: str, env: dict, tmp: str) -> dict:
    """One ``rigfem check final-cm`` process (exit 0 or 1); its result folder measured."""
    out = Path(tmp) / f"out-{len(list(Path(tmp).glob('out-*')))}"
    r = _rigfem(["check", "final-cm", "--fidelity", fidelity, "--out", str(out), "--quiet"], env, ok=(0, 1))
    size = measure(out)
    return r | {"folder_mb": size["total_bytes"] / 1e6, "folder_files": size["files"],
                "folder_kinds_mb": {k: size[f"{k}_bytes"] / 1e6 for k in FOLDER_KINDS}}


def row_check(a: argparse.Namespace, tree: Path) -> dict[str, list]:
    out = {}
    for fid in a.fidelity:
        out[f"check {fid} cold"], out[f"check {fid} warm"] = cold_warm(
            lambda env, tmp: _check(fid, env, tmp), tree, a.repeats or 3)
    return out


def row_light(a: argparse.Namespace, tree: Path) -> dict[str, list]:
    out = {}
    for name, argv in LIGHT.items():
        out[f"{name} cold"], out[f"{name} warm"] = cold_warm(lambda env, tmp: _rigfem(argv, env), tree,
                                                             a.repeats or 3)
    return out


def row_synth(a: argparse.Namespace, tree: Path) -> dict[str, list]:
    cold, _ = cold_warm(lambda env, tmp: _rigfem(SYNTH, env, ok=(0, 1)), tree, a.repeats or 3, warm=False)
    return {"synthesize --rig cold": cold}


def row_sweep(a: argparse.Namespace, tree: Path) -> dict[str, list]:
    import bench_sweep

    cold, warm = cold_warm(lambda env, tmp: _sample(bench_sweep._sweep(2, {**env, **ONE_THREAD})), tree,
                           a.repeats or 1)
    return {"sweep cold": cold, "sweep warm": warm}


#: rigfem's FE steps on the CalculiX row's mesh (benchmarks/bench_calculix.py), its profile
CCX_STEPS = ("assembly", "supports_loads", "factorise", "solve", "stress", "fe_total")


def row_ccx(a: argparse.Namespace, tree: Path) -> dict[str, list]:
    """The tree's benchmarks/bench_calculix.py in its own process, its record written to a scratch folder."""
    with tempfile.TemporaryDirectory(prefix="perf-") as tmp:
        r = timed_process([sys.executable, str(tree / "benchmarks" / "bench_calculix.py"), "--repeats",
                           str(a.repeats or 1), "--threads", "1", "--cases", "4", "--out", tmp],
                          env=env_of(tmp, tree))
        if r["exit"]:
            raise SystemExit(f"bench_calculix.py exited {r['exit']}: {r['stderr_tail']}")
        rec = json.loads((Path(tmp) / "calculix_vs_rigfem.json").read_text())
    steps = {k: rec["summary"]["rigfem"][k]["median"] for k in CCX_STEPS}
    return {"ccx": [_sample(r) | {"ratio": rec["derived"]["FE wall ratio rigfem / ccx"],
                                  "dof": rec["params"]["mesh"]["dof"], "rigfem_steps_s": steps,
                                  "ccx_s": rec["summary"]["ccx"]["wall"]["median"]}]}


def row_dof(a: argparse.Namespace, tree: Path) -> dict[str, list]:
    """One process per mesh (benchmarks/bench_fe.py --rss-nx): its peak tree RSS against its DOF;
    stops at the first mesh the machine does not take (the process fails or is killed)."""
    out, failed = [], []
    for nx in a.dof_nx:
        with tempfile.TemporaryDirectory(prefix="perf-") as tmp:
            r = timed_process([sys.executable, str(tree / "benchmarks" / "bench_fe.py"), "--rss-nx", str(nx)],
                              env=env_of(tmp, tree))
        if r["exit"]:
            print(f"dof: nx {nx} failed ({r['exit']}): the largest mesh this machine takes is the one before",
                  file=sys.stderr)
            failed.append(_sample(r) | {"nx": nx})
            break
        out.append(_sample(r) | {"nx": nx, **json.loads(r["stdout_tail"].strip().splitlines()[-1])})
        print(f"dof: {out[-1]['dof']:,} DOF, peak {out[-1]['peak_tree_rss_mib']:.0f} MiB", file=sys.stderr)
    return ({"dof": out} if out else {}) | ({"dof failed": failed} if failed else {})


def calibration() -> dict:
    """One timed calibration process: the factorisation's seconds (:data:`CALIBRATION`)."""
    r = timed_process([sys.executable, "-c", CALIBRATION], env=cold_env(tempfile.gettempdir(), **ONE_THREAD))
    if r["exit"]:
        raise SystemExit(f"calibration exited {r['exit']}: {r['stderr_tail']}")
    return {"seconds": float(r["stdout_tail"].strip().splitlines()[-1]), "load_before": r["load_before"]}


@contextlib.contextmanager
def baseline_tree(rev: str):
    """A temporary detached worktree of ``rev`` (bytecode compiled, as an install would), removed after."""
    with tempfile.TemporaryDirectory(prefix="perf-baseline-") as tmp:
        path = Path(tmp) / "tree"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(path), rev], check=True)
        try:
            compileall.compile_dir(path / "rigfem", quiet=1)
            yield path
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(path)], check=True)


def fit(points: list[tuple[float, float]]) -> dict:
    """Least-squares line y = a + b·x through the points, with its R²."""
    n = len(points)
    mx, my = sum(x for x, _ in points) / n, sum(y for _, y in points) / n
    sxx = sum((x - mx) ** 2 for x, _ in points)
    b = sum((x - mx) * (y - my) for x, y in points) / sxx if sxx else 0.0
    ss = sum((y - my) ** 2 for _, y in points)
    res = sum((y - my - b * (x - mx)) ** 2 for x, y in points)
    return {"intercept": my - b * mx, "slope": b, "r2": 1 - res / ss if ss else 1.0}


def derive(samples: dict[str, list]) -> dict:
    """The figures computed from the samples: the DOF row's linear fit (MiB per 1000 DOF), every
    median wall time in calibrations (the calibration's median of the same run), and after / before."""
    out: dict = {}
    pts = [(s["dof"], s["peak_tree_rss_mib"]) for s in samples.get("dof", [])]
    if len(pts) >= 2:
        f = fit(pts)
        out |= {"dof MiB per 1000 DOF": 1000 * f["slope"], "dof intercept MiB": f["intercept"], "dof R2": f["r2"],
                "dof largest": max(x for x, _ in pts)}
    cal = [s["seconds"] for s in samples.get("calibration", [])]
    walls = {k: statistics.median(s["wall_s"] for s in v) for k, v in samples.items() if v and "wall_s" in v[0]}
    if cal:
        out["calibration median s"] = statistics.median(cal)
        out |= {f"{k} / calibration": w / out["calibration median s"] for k, w in walls.items()}
    out |= {f"{k} after / before": walls[k] / walls[f"before: {k}"] for k in walls if f"before: {k}" in walls}
    for k in ("check standard cold", "check draft cold"):
        b, n = samples.get(f"before: {k}"), samples.get(k)
        if b and n and "folder_mb" in b[0] and "folder_mb" in n[0]:
            out[f"{k} folder after / before"] = n[0]["folder_mb"] / b[0]["folder_mb"]
    return out


def status(rec: dict, prefix: str = "") -> list[dict]:
    """Every row of :data:`GOALS` against the record's series named ``prefix + series`` (``"before: "``:
    the baseline's): cold, warm, peak RSS, folder size (medians) and met / not met."""
    s, d, out = rec["summary"], rec["derived"], []
    for row, g in GOALS.items():
        name = SERIES.get(row, row)
        cold = s.get(f"{prefix}{name} cold") or s.get(f"{prefix}{name}")
        warm = None if row in SERIES else s.get(f"{prefix}{name} warm")
        # a ratio, DOF or folder row's wall time is its whole benchmark's, not a figure of its goal
        timed = cold and not {"ratio", "dof", "folder_mb"} & g.keys()
        v = {"row": row, "work": g["work"], "goal": g["goal"], "cold_s": cold["wall_s"]["median"] if timed else None,
             "warm_s": warm["wall_s"]["median"] if warm else None,
             "rss_mib": cold["peak_tree_rss_mib"]["max"] if timed else None}
        checks = [v[k] < g[k] for k in ("cold_s", "warm_s", "rss_mib") if k in g and v[k] is not None]
        if "folder_mb" in g and cold and "folder_mb" in cold:
            v["folder_mb"] = cold["folder_mb"]["max"]
            checks.append(v["folder_mb"] < g["folder_mb"])
        if "ratio" in g and cold:
            v["ratio"] = cold["ratio"]["median"]
            checks.append(v["ratio"] <= g["ratio"])
        if "dof" in g and "dof largest" in d and not prefix:
            v["dof"], v["r2"] = d["dof largest"], d["dof R2"]
            # the goal's size, or a larger mesh the machine did not take (a "dof failed" run)
            checks += [d["dof largest"] >= g["dof"] or "dof failed" in s, d["dof R2"] >= g["r2"]]
        missing = [k for k in ("cold_s", "warm_s", "rss_mib", "folder_mb", "ratio", "dof") if k in g and v.get(k) is None]
        v["met"] = None if missing else all(checks)  # None: not (fully) measured
        out.append(v)
    return out


def merge(samples: dict[str, list], old: dict | None, baseline: dict | None) -> tuple[dict, dict]:
    """This run's series over the previous record's; provenance (date, commit, dirty) of each series.
    Another baseline drops the old one's series (a record's before/after compare one baseline)."""
    now = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), **{
        k: v for k, v in zip(("commit", "dirty"), commit().values())}}
    old_base = ((old or {}).get("params", {}).get("baseline") or {}).get("commit")
    drop = (lambda k: k.startswith("before: ")) if baseline and baseline["commit"] != old_base else (lambda k: False)
    keep = {k: v for k, v in (old or {}).get("samples", {}).items() if k not in samples and not drop(k)}
    whole = {"date": old["date"], "commit": old["commit"]["sha"], "dirty": old["commit"]["dirty"]} if old else {}
    said = (old or {}).get("params", {}).get("provenance", {})
    prov = {k: said.get(k, whole) for k in keep}  # a series without its own: the old record's date and commit
    ours = {k: (now | baseline if k.startswith("before: ") and baseline else now) for k in samples}
    return {**keep, **samples}, {**prov, **ours}


def print_goals(rec: dict) -> None:
    before = {v["row"]: v for v in status(rec, "before: ")}
    for v in status(rec):
        met = {None: "not measured", True: "met", False: "NOT MET"}[v["met"]]
        figs = ", ".join(f"{k} {v[k]:.3g}" + (f" (before {before[v['row']][k]:.3g})" if before[v["row"]].get(k)
                                               else "")
                         for k in ("cold_s", "warm_s", "rss_mib", "folder_mb", "ratio", "dof") if v.get(k))
        print(f"{v['row']:17s} {met:12s} goal {v['goal']}; {figs or '-'}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", nargs="+", choices=ROWS, help=f"rows to measure (default all: {' '.join(ROWS)})")
    ap.add_argument("--repeats", type=int, help="runs per series (default 3; 1 for the sweep, CalculiX and DOF rows)")
    ap.add_argument("--fidelity", nargs="+", default=["standard", "draft"], choices=["standard", "draft"])
    ap.add_argument("--dof-nx", type=int, nargs="+", default=list(DOF_NX), help="bar divisions of the DOF row")
    ap.add_argument("--baseline", metavar="REV", help=f"also measure the rows {', '.join(COMPARED)} with the code "
                                                      "of REV, interleaved (before/after in one run)")
    ap.add_argument("--allow-dirty", action="store_true", help="write a record from a modified work tree "
                                                                "(the record says so)")
    ap.add_argument("--goals", action="store_true", help="print each row against its goal (alone: measure nothing)")
    ap.add_argument("--out", type=Path, default=OUT, help="record folder (default results/benchmarks)")
    a = ap.parse_args(argv)
    if a.repeats is not None and a.repeats < 1:
        ap.error(f"--repeats = {a.repeats}: must be 1 or more")
    path = a.out / "perf.json"
    old = json.loads(path.read_text()) if path.is_file() else None
    if a.goals and not a.rows:
        if old is None:
            raise SystemExit(f"no record {path}: run python benchmarks/bench_perf.py first")
        print_goals(old)
        return 0
    if commit()["dirty"] and not a.allow_dirty:
        raise SystemExit("the work tree has uncommitted changes: commit them, or pass --allow-dirty")
    compileall.compile_dir(ROOT / "rigfem", quiet=1)  # bytecode as a regular install has it
    samples: dict[str, list] = {}
    with contextlib.ExitStack() as stack:
        base = None
        if a.baseline:
            sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", a.baseline], capture_output=True,
                                 text=True, check=True).stdout.strip()
            base = {"commit": sha, "dirty": False, "baseline": a.baseline}
            tree = stack.enter_context(baseline_tree(sha))
            runs_code_of(tree)
        runs_code_of(ROOT)
        for row in a.rows or ROWS:
            samples.setdefault("calibration", []).append(calibration())
            if base and row in COMPARED:
                samples.update({f"before: {k}": v for k, v in globals()[f"row_{row}"](a, tree).items()})
            samples.update(globals()[f"row_{row}"](a, ROOT))
            merged, prov = merge(samples, old, base)  # after every row: an interrupted run keeps what it measured
            kept = base or (old or {}).get("params", {}).get("baseline")  # the baseline of the kept "before" series
            write_record("perf", merged, derive(merged), {"provenance": prov, "fidelity": a.fidelity,
                                                          "repeats": a.repeats, "baseline": kept, "goals": GOALS},
                         out=a.out)
            print(f"{row}: measured", file=sys.stderr, flush=True)
    rec = json.loads(path.read_text())
    if a.goals:
        print_goals(rec)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
