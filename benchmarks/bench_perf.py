"""Issue 26's performance table in one command: every row cold and warm, each run a separate process.

    python benchmarks/bench_perf.py                      # every row (long: the sweep, --rig, 1M DOF)
    python benchmarks/bench_perf.py --rows light check --repeats 1 --fidelity draft
    python benchmarks/bench_perf.py --goals              # measure nothing: the record against the goals

Each run is its own process (benchmarks/record.timed_process: wall time, peak RSS of its whole
process tree, load average).  *Cold*: empty rigfem and numba caches; *warm*: the caches the cold
run filled.  Writes results/benchmarks/perf.json (rows measured before and not re-measured are
kept, each series with the date and commit it was measured at); ``python benchmarks/publish.py``
writes perf.md and README's Performance table, each row met / not met against :data:`GOALS`.
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys
import tempfile
from pathlib import Path

from record import OUT, cold_env, commit, timed_process, write_record

#: the one home of the goals (issue 26): row -> the work, the goal as written, the limits it sets
#: (cold_s / warm_s: median wall time; rss_mib: peak tree RSS of every run; ratio: rigfem/ccx;
#: dof: the largest DOF measured, r2: the linear fit's R²)
GOALS: dict[str, dict] = {
    "check standard": {"work": "`rigfem check final-cm --force`, standard", "goal": "cold < 30 s, < 1.5 GB; warm < 5 s",
                       "cold_s": 30.0, "warm_s": 5.0, "rss_mib": 1536.0},
    "check draft": {"work": "`rigfem check final-cm --force --fidelity draft`", "goal": "warm < 3 s", "warm_s": 3.0},
    "help": {"work": "`rigfem --help`", "goal": "< 0.3 s", "cold_s": 0.3, "warm_s": 0.3},
    "version": {"work": "`rigfem --version`", "goal": "< 0.3 s", "cold_s": 0.3, "warm_s": 0.3},
    "parts": {"work": "`rigfem parts`", "goal": "< 0.3 s", "cold_s": 0.3, "warm_s": 0.3},
    "kinematics": {"work": "`rigfem kinematics mech2-fourbar-coupler-point`", "goal": "< 0.3 s",
                   "cold_s": 0.3, "warm_s": 0.3},
    "synthesize --rig": {"work": "`rigfem synthesize motion --points 0,0 -15.12,-9 -29.128,-4 --rig --top 3`",
                         "goal": "cold < 60 s, < 2 GB, with progress", "cold_s": 60.0, "rss_mib": 2048.0},
    "sweep": {"work": "`rigfem sweep --four-bar` (2 workers), end to end", "goal": "cold < 3 min, warm < 30 s",
              "cold_s": 180.0, "warm_s": 30.0},
    "ccx": {"work": "one part solve vs CalculiX on the same mesh (700 mm rail, P2, 1 thread)",
            "goal": "FE wall ratio rigfem/ccx ≤ 0.4", "ratio": 0.4},
    "dof": {"work": "peak RSS against DOF (P2 bar 700 × 23 × 24 mm, factorise and solve)",
            "goal": "linear, up to 1M DOF or the largest mesh the machine takes", "dof": 1e6, "r2": 0.98},
}
#: the README command of each light row (argv after ``rigfem``)
LIGHT = {"help": ["--help"], "version": ["--version"], "parts": ["parts"],
         "kinematics": ["kinematics", "mech2-fourbar-coupler-point"]}
SYNTH = ["synthesize", "motion", "--points", "0,0", "-15.12,-9", "-29.128,-4", "--rig", "--top", "3"]
#: bar divisions along its length for the DOF row: 726·nx + 363 DOF (P2, 5 × 5 divisions across)
DOF_NX = (35, 70, 140, 280, 560, 1100, 1378)
HERE = Path(__file__).resolve().parent
ROWS = ("check", "light", "synth", "sweep", "ccx", "dof")


def _sample(r: dict) -> dict:
    """A run's sample without its output text (kept: wall, peak tree RSS, exit, load averages)."""
    return {k: v for k, v in r.items() if not k.endswith("_tail")}


def _rigfem(args: list[str], env: dict, ok: tuple[int, ...] = (0,)) -> dict:
    """One ``python -m rigfem ARGS`` process; refuses an unexpected exit code."""
    r = timed_process([sys.executable, "-m", "rigfem", *args], env=env)
    if r["exit"] not in ok:
        raise SystemExit(f"rigfem {' '.join(args)} exited {r['exit']}: {r['stderr_tail']}")
    return _sample(r)


def cold_runs(run, repeats: int) -> list:
    """``repeats`` runs, each on fresh caches of its own (a second run on the first's would be warm)."""
    cold = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory(prefix="perf-") as tmp:
            cold.append(run(cold_env(tmp), tmp))
    return cold


def cold_warm(run, repeats: int) -> tuple[list, list]:
    """``repeats`` cold runs (:func:`cold_runs`), then ``repeats`` warm runs on the caches one filled."""
    cold = cold_runs(run, repeats)
    with tempfile.TemporaryDirectory(prefix="perf-") as tmp:
        env = cold_env(tmp)
        run(env, tmp)  # fills both caches
        warm = [run(env, tmp) for _ in range(repeats)]
    return cold, warm


def row_check(a: argparse.Namespace) -> dict[str, list]:
    import bench_check

    out = {}
    for fid in a.fidelity:
        out[f"check {fid} cold"], out[f"check {fid} warm"] = cold_warm(
            lambda env, tmp: _sample(bench_check._run("final-cm", fid, env)), a.repeats or 1)
    return out


def row_light(a: argparse.Namespace) -> dict[str, list]:
    out = {}
    for name, argv in LIGHT.items():
        out[f"{name} cold"], out[f"{name} warm"] = cold_warm(lambda env, tmp: _rigfem(argv, env), a.repeats or 3)
    return out


def row_synth(a: argparse.Namespace) -> dict[str, list]:
    return {"synthesize --rig cold": cold_runs(lambda env, tmp: _rigfem(SYNTH, env, ok=(0, 1)), a.repeats or 1)}


def row_sweep(a: argparse.Namespace) -> dict[str, list]:
    import bench_sweep

    threads = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    cold, warm = cold_warm(lambda env, tmp: _sample(bench_sweep._sweep(2, {**env, **threads})), a.repeats or 1)
    return {"sweep cold": cold, "sweep warm": warm}


def row_ccx(a: argparse.Namespace) -> dict[str, list]:
    """benchmarks/bench_calculix.py in its own process, its record written to a scratch folder."""
    with tempfile.TemporaryDirectory(prefix="perf-") as tmp:
        r = timed_process([sys.executable, str(HERE / "bench_calculix.py"), "--repeats", str(a.repeats or 1),
                           "--threads", "1", "--cases", "4", "--out", tmp], env=cold_env(tmp))
        if r["exit"]:
            raise SystemExit(f"bench_calculix.py exited {r['exit']}: {r['stderr_tail']}")
        rec = json.loads((Path(tmp) / "calculix_vs_rigfem.json").read_text())
    return {"ccx": [_sample(r) | {"ratio": rec["derived"]["FE wall ratio rigfem / ccx"],
                                  "dof": rec["params"]["mesh"]["dof"]}]}


def row_dof(a: argparse.Namespace) -> dict[str, list]:
    """One process per mesh (benchmarks/bench_fe.py --rss-nx): its peak tree RSS against its DOF;
    stops at the first mesh the machine does not take (the process fails or is killed)."""
    out, failed = [], []
    for nx in a.dof_nx:
        with tempfile.TemporaryDirectory(prefix="perf-") as tmp:
            r = timed_process([sys.executable, str(HERE / "bench_fe.py"), "--rss-nx", str(nx)], env=cold_env(tmp))
        if r["exit"]:
            print(f"dof: nx {nx} failed ({r['exit']}): the largest mesh this machine takes is the one before",
                  file=sys.stderr)
            failed.append(_sample(r) | {"nx": nx})
            break
        out.append(_sample(r) | {"nx": nx, **json.loads(r["stdout_tail"].strip().splitlines()[-1])})
        print(f"dof: {out[-1]['dof']:,} DOF, peak {out[-1]['peak_tree_rss_mib']:.0f} MiB", file=sys.stderr)
    return ({"dof": out} if out else {}) | ({"dof failed": failed} if failed else {})


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
    """The figures computed from the samples: the DOF row's linear fit (MiB per 1000 DOF)."""
    pts = [(s["dof"], s["peak_tree_rss_mib"]) for s in samples.get("dof", [])]
    if len(pts) < 2:
        return {}
    f = fit(pts)
    return {"dof MiB per 1000 DOF": 1000 * f["slope"], "dof intercept MiB": f["intercept"], "dof R2": f["r2"],
            "dof largest": max(x for x, _ in pts)}


def status(rec: dict) -> list[dict]:
    """Every row of :data:`GOALS` against the record: cold, warm, peak RSS (medians) and met / not met."""
    s, d, out = rec["summary"], rec["derived"], []
    for row, g in GOALS.items():
        cold, warm = s.get(f"{row} cold") or s.get(row), s.get(f"{row} warm")
        runs = [x for x in (cold, warm) if x]
        # a ratio or DOF row's wall time is its whole benchmark's, not a figure of its goal
        timed = cold and not {"ratio", "dof"} & g.keys()
        v = {"row": row, "work": g["work"], "goal": g["goal"], "cold_s": cold["wall_s"]["median"] if timed else None,
             "warm_s": warm["wall_s"]["median"] if warm else None,
             "rss_mib": max(x["peak_tree_rss_mib"]["max"] for x in runs) if runs else None}
        checks = [v[k] < g[k] for k in ("cold_s", "warm_s", "rss_mib") if k in g and v[k] is not None]
        if "ratio" in g and cold:
            v["ratio"] = cold["ratio"]["median"]
            checks.append(v["ratio"] <= g["ratio"])
        if "dof" in g and "dof largest" in d:
            v["dof"], v["r2"] = d["dof largest"], d["dof R2"]
            # the goal's size, or a larger mesh the machine did not take (a "dof failed" run)
            checks += [d["dof largest"] >= g["dof"] or "dof failed" in s, d["dof R2"] >= g["r2"]]
        missing = [k for k in ("cold_s", "warm_s", "ratio", "dof") if k in g and v.get(k) is None]
        v["met"] = None if missing else all(checks)  # None: not (fully) measured
        out.append(v)
    return out


def merge(samples: dict[str, list], old: dict | None) -> tuple[dict, dict]:
    """This run's series over the previous record's; provenance (date, commit) of each series."""
    now = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "commit": commit()["sha"]}
    keep = {k: v for k, v in (old or {}).get("samples", {}).items() if k not in samples}
    prov = {k: v for k, v in (old or {}).get("params", {}).get("provenance", {}).items() if k in keep}
    return {**keep, **samples}, {**prov, **{k: now for k in samples}}


def print_goals(rec: dict) -> None:
    for v in status(rec):
        met = {None: "not measured", True: "met", False: "NOT MET"}[v["met"]]
        figs = ", ".join(f"{k} {v[k]:.3g}" for k in ("cold_s", "warm_s", "rss_mib", "ratio", "dof") if v.get(k))
        print(f"{v['row']:17s} {met:12s} goal {v['goal']}; {figs or '-'}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", nargs="+", choices=ROWS, help=f"rows to measure (default all: {' '.join(ROWS)})")
    ap.add_argument("--repeats", type=int, help="runs per series (default 3 for light, 1 for the long rows)")
    ap.add_argument("--fidelity", nargs="+", default=["standard", "draft"], choices=["standard", "draft"])
    ap.add_argument("--dof-nx", type=int, nargs="+", default=list(DOF_NX), help="bar divisions of the DOF row")
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
    samples: dict[str, list] = {}
    for row in a.rows or ROWS:
        samples.update(globals()[f"row_{row}"](a))
        merged, prov = merge(samples, old)  # after every row: an interrupted run keeps what it measured
        write_record("perf", merged, derive(merged), {"provenance": prov, "fidelity": a.fidelity,
                                                      "repeats": a.repeats, "goals": GOALS}, out=a.out)
        print(f"{row}: measured", file=sys.stderr, flush=True)
    rec = json.loads(path.read_text())
    if a.goals:
        print_goals(rec)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
