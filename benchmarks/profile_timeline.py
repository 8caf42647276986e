"""Where a command's wall time and memory go: its stages on a clock, cold or warm, one process each.

    python benchmarks/profile_timeline.py                       # check final-cm standard, sweep, synthesize --rig
    python benchmarks/profile_timeline.py --only check --state warm
    python benchmarks/profile_timeline.py --baseline 450ffeb       # the check also with 450ffeb's code

Each command runs as a user runs it (``python -m rigfem ...``, the command line's own observer),
with the observer's stage events time-stamped and the peak RSS of the whole process tree (the
mesher, solver and picture children included) sampled every 50 ms and attributed to the stage
running then.  A stage's time is the wall time from its start to the next stage's (stages run one
after another; what runs inside a stage in parallel shows as its width, not as a sum).  Unlike a
cProfile of the main process, this counts the children's work where the user waits for it.
Writes results/benchmarks/timeline.json (``python benchmarks/publish.py`` writes timeline.md).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_perf import ONE_THREAD, SYNTH, baseline_tree, env_of, merge, runs_code_of
from record import OUT, ROOT, commit, timed_process, write_record

#: command -> argv after ``rigfem`` (the out folder is added)
COMMANDS = {"check": ["check", "final-cm", "--quiet"], "check draft": ["check", "final-cm", "--fidelity", "draft",
                                                                         "--quiet"],
            "synthesize --rig": SYNTH, "sweep": ["sweep", "--four-bar", "--workers", "2", "--quiet"]}
#: runs inside the measured process: the command line with its observer's events time-stamped and a
#: thread sampling the process tree's RSS
PROBE = r"""
import json, sys, threading, time
t0 = time.perf_counter()
BEFORE = "before the first stage: imports, arguments, the command's first work"
events, peak = [[0.0, "start", 0.0]], [0.0]
def rss():
    import psutil
    root = psutil.Process()
    total = 0
    for q in [root, *root.children(recursive=True)]:
        try:
            total += q.memory_info().rss
        except psutil.NoSuchProcess:
            pass
    return total / 2**20
def sample():
    while True:
        peak[0] = max(peak[0], rss())
        time.sleep(0.05)
threading.Thread(target=sample, daemon=True).start()
def mark(text):
    events.append([time.perf_counter() - t0, text, peak[0]])
    peak[0] = 0.0
import rigfem.cli.progress as progress
mark(BEFORE)
base = progress._Progress
class Timed(base):
    def stage(self, text):
        mark(text)
        super().stage(text)
    def decided(self, report):
        mark("verdict known; writing the result folder")
        super().decided(report)
progress.OBSERVER.__class__ = Timed
from rigfem.cli import main
try:
    code = main(sys.argv[2:])
finally:
    mark("end")
    with open(sys.argv[1], "w") as f:
        json.dump(events, f)
sys.exit(code)
"""


def timeline(argv: list[str], env: dict) -> dict:
    """One run of ``rigfem ARGV`` with :data:`PROBE`: its stages (name, start s, seconds, peak MiB)."""
    with tempfile.TemporaryDirectory(prefix="timeline-") as tmp:
        r = timed_process([sys.executable, "-c", PROBE, f"{tmp}/events.json", *argv], env=env)
        if r["exit"] not in (0, 1):
            raise SystemExit(f"rigfem {' '.join(argv)} exited {r['exit']}: {r['stderr_tail']}")
        ev = json.loads(Path(f"{tmp}/events.json").read_text())
    stages = [{"stage": name, "start_s": t, "seconds": ev[k + 1][0] - t, "peak_tree_rss_mib": ev[k + 1][2]}
              for k, (t, name, _) in enumerate(ev[:-1])]
    return {"wall_s": r["wall_s"], "peak_tree_rss_mib": r["peak_tree_rss_mib"], "exit": r["exit"],
            "load_before": r["load_before"], "stages": stages}


def run_all(names: list[str], states: list[str], tree: Path, prefix: str, samples: dict) -> None:
    """Each command of ``names`` with the code of ``tree``: cold, then warm on the caches it filled
    (if asked), its samples named ``prefix + command + state``."""
    for name in names:
        with tempfile.TemporaryDirectory(prefix="timeline-") as tmp:
            env = env_of(tmp, tree, **(ONE_THREAD if name == "sweep" else {}))
            for k, state in enumerate(s for s in ("cold", "warm") if s in states or s == "cold"):
                out = [] if name == "synthesize --rig" else ["--out", str(Path(tmp) / f"out-{k}")]
                run = timeline([*COMMANDS[name], *out], env)
                if state in states:
                    samples[f"{prefix}{name} {state}"] = [run]
                    print(f"{prefix}{name} {state}: {run['wall_s']:.1f} s, {run['peak_tree_rss_mib']:.0f} MiB",
                          flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", choices=list(COMMANDS), default=list(COMMANDS))
    ap.add_argument("--state", nargs="+", choices=["cold", "warm"], default=["cold", "warm"])
    ap.add_argument("--baseline", metavar="REV", help="also run the commands of --baseline-only with the code of REV "
                                                      "(series 'before: ...'), each right before this checkout's")
    ap.add_argument("--baseline-only", nargs="+", choices=list(COMMANDS), default=["check"],
                    help="the commands --baseline runs (default: check)")
    ap.add_argument("--allow-dirty", action="store_true", help="write a record from a modified work tree")
    ap.add_argument("--out", type=Path, default=OUT, help="record folder (default results/benchmarks)")
    a = ap.parse_args(argv)
    if commit()["dirty"] and not a.allow_dirty:
        raise SystemExit("the work tree has uncommitted changes: commit them, or pass --allow-dirty")
    samples: dict[str, list] = {}
    base = None
    with contextlib.ExitStack() as stack:
        if a.baseline:
            sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", a.baseline], capture_output=True, text=True,
                                 check=True).stdout.strip()
            tree, base = stack.enter_context(baseline_tree(sha)), {"commit": sha, "dirty": False, "baseline": a.baseline}
            runs_code_of(tree)
        runs_code_of(ROOT)
        for name in a.only:
            if base and name in a.baseline_only:
                run_all([name], a.state, tree, "before: ", samples)
            run_all([name], a.state, ROOT, "", samples)
    path = a.out / "timeline.json"
    old = json.loads(path.read_text()) if path.is_file() else None
    merged, prov = merge(samples, old, base)  # the commands not run again keep their series
    params = {"commands": {k: COMMANDS[k] for k in a.only}, "provenance": prov,
              "baseline": base or (old or {}).get("params", {}).get("baseline")}
    print(f"wrote {write_record('timeline', merged, {}, params, out=a.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
