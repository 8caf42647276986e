"""The reference scenes' verdicts and peaks, with REV's code and this checkout's, on the same meshes.

    python benchmarks/bench_same_results.py --baseline 450ffeb

Issue 41 asks a faster rigfem to leave every verdict and peak of the reference scenes unchanged
(same mesh, 1e-9).  Each scene is checked as tests/test_reference_scenes.py checks it (the
committed report's fidelity, no animation frames, no pictures), each check its own process with
empty caches, by REV's code (a temporary git worktree) and by this checkout's, ``--repeats`` times
each, interleaved.  Every run has one MKL/OpenMP thread: PARDISO's rounding depends on how many
threads the OpenMP runtime gives it, and a busy machine changes that from run to run (two runs of
the same code on two threads differ in the ninth digit); on one thread a run is reproducible, so a
difference between the two sides is the code's.  The repeats show that (run-to-run difference of
each side).  Writes results/benchmarks/same_results.json (``python benchmarks/publish.py``: its .md).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_perf import ONE_THREAD, baseline_tree, env_of, runs_code_of
from record import ROOT, commit, timed_process, write_record

SCENES = ("final-cm", "final-nc", "final-nm", "slider-crank-300-840")
#: a part case's figures compared (report.json), the peak first
FIGURES = ("peak_mpa", "error_pct", "utilisation_pct", "max_displacement_mm", "crank_deg")
#: what must be equal for "the same mesh" and "the same verdict"
SAME = ("verdict", "mesh.level", "mesh.fe_nodes", "mesh.tets")

CHILD = """
import json, sys
from pathlib import Path
from rigfem.pipeline import Output, Request, run_check
scene, committed, out = sys.argv[1], json.loads(Path(sys.argv[2]).read_text()), Path(sys.argv[3])
run_check(Request(scene, {"fidelity": committed["settings"]["fidelity"], "frames": 0},
                  bool(committed["rule_violations"])), Output(out, pictures=False))
"""


def _get(d: dict, dotted: str):
    for k in dotted.split("."):
        d = d[k]
    return d


def part_figures(report: dict) -> dict[str, dict]:
    """``"<part> <mode>"`` -> its figures and identity fields (:data:`FIGURES`, :data:`SAME`)."""
    return {f"{p['name']} {p['mode']}": {k: _get(p, k) for k in FIGURES + SAME} for p in report["parts"]}


def rel(a: float, b: float) -> float:
    return 0.0 if a == b else abs(a - b) / max(abs(a), abs(b))


def compare(old: dict, new: dict) -> dict:
    """The largest relative difference of each figure over the part cases, the cases whose verdict or
    mesh differ, and the cases whose figures are bit for bit the same."""
    a, b = part_figures(old), part_figures(new)
    out = {"cases": sorted(a.keys() | b.keys()), "missing": sorted(a.keys() ^ b.keys())}
    both = sorted(a.keys() & b.keys())
    out["rel"] = {f: max((rel(a[c][f], b[c][f]) for c in both), default=0.0) for f in FIGURES}
    out["worst_peak_case"] = max(both, key=lambda c: rel(a[c]["peak_mpa"], b[c]["peak_mpa"]), default=None)
    out["different"] = [f"{c}: {f} {a[c][f]} -> {b[c][f]}" for c in both for f in SAME if a[c][f] != b[c][f]]
    out["bit for bit"] = [c for c in both if all(a[c][f] == b[c][f] for f in FIGURES)]
    return out


def run_scene(scene: str, tree: Path) -> dict:
    """One check of ``scene`` by ``tree``'s code, its own process and caches: its report."""
    with tempfile.TemporaryDirectory(prefix="same-") as tmp:
        out = Path(tmp) / "out"
        r = timed_process([sys.executable, "-c", CHILD, scene, str(ROOT / "results" / scene / "report.json"),
                           str(out)], env=env_of(tmp, tree, **ONE_THREAD))
        if r["exit"] not in (0, 1):
            raise SystemExit(f"{scene} with {tree}: exit {r['exit']}: {r['stderr_tail']}")
        return {"wall_s": r["wall_s"], "report": json.loads((out / "report.json").read_text())}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", metavar="REV", required=True, help="the code to compare with (a git revision)")
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=SCENES)
    ap.add_argument("--repeats", type=int, default=2, help="checks of each scene per side (default 2)")
    ap.add_argument("--allow-dirty", action="store_true", help="write a record from a modified work tree")
    a = ap.parse_args(argv)
    if a.repeats < 1:
        ap.error(f"--repeats = {a.repeats}: must be 1 or more")
    if commit()["dirty"] and not a.allow_dirty:
        raise SystemExit("the work tree has uncommitted changes: commit them, or pass --allow-dirty")
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", a.baseline], capture_output=True, text=True,
                         check=True).stdout.strip()
    samples: dict[str, list] = {}
    with contextlib.ExitStack() as stack:
        base = stack.enter_context(baseline_tree(sha))
        runs_code_of(base)
        runs_code_of(ROOT)
        for scene in a.scenes:
            runs = {"before": [], "after": []}
            for _ in range(a.repeats):
                for side, tree in (("before", base), ("after", ROOT)):
                    runs[side].append(run_scene(scene, tree))
                    print(f"{scene} {side}: {runs[side][-1]['wall_s']:.0f} s", file=sys.stderr, flush=True)
            first = {s: r[0]["report"] for s, r in runs.items()}
            row = {"wall_before_s": runs["before"][0]["wall_s"], "wall_after_s": runs["after"][0]["wall_s"],
                   "before -> after": compare(first["before"], first["after"])}
            for side in runs:
                row[f"{side}, run to run"] = [compare(first[side], r["report"]) for r in runs[side][1:]]
            samples[scene] = [row]
    repeat = max((c["rel"]["peak_mpa"] for s in samples.values() for side in ("before", "after")
                  for c in s[0][f"{side}, run to run"]), default=None)
    derived = {"largest peak difference before -> after": max(s[0]["before -> after"]["rel"]["peak_mpa"]
                                                               for s in samples.values()),
               "largest peak difference run to run": repeat,
               "verdicts and meshes the same": all(not s[0]["before -> after"]["different"]
                                                   and not s[0]["before -> after"]["missing"] for s in samples.values()),
               "part cases compared": sum(len(s[0]["before -> after"]["cases"]) for s in samples.values())}
    path = write_record("same_results", samples, derived,
                        {"baseline": {"rev": a.baseline, "commit": sha}, "repeats": a.repeats, "threads": 1,
                         "figures": list(FIGURES), "same": list(SAME)})
    print(json.dumps(derived, indent=1))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
