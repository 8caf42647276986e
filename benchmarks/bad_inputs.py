"""Issue 24's examples, tried as a new user would: what rigfem prints now and how long it takes to
fail (wall time, exit code, peak memory of the process tree, the last line on stderr).

    python benchmarks/bad_inputs.py

Each example runs as its own `python -m rigfem ...` process in a temporary folder with an empty
rigfem cache.  Ctrl-C during meshing: SIGINT once gmsh has been meshing a fine part for 4 s; the
time is from the signal to the process's end, and the folder must hold nothing afterwards.
`| head`: the first line of a long JSON output read by `head -1` (bash, exit status of rigfem).
Writes results/benchmarks/bad_inputs.json (``benchmarks/publish.py`` writes the .md).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from record import cold_env, timed_process, write_record

RIGFEM = [sys.executable, "-m", "rigfem"]
FN = ["--input", "20", "90", "--output", "80", "90", "--ground", "2"]

#: example -> the command (after ``rigfem``)
EXAMPLES = {
    "100 m rail": ["mesh", "rail_size25", "--length", "100000", "--out", "r.vtu"],
    "10**9 samples (reactions)": ["reactions", "--samples", "1000000000"],
    "10**9 samples (kinematics)": ["kinematics", "--samples", "1e9"],
    "sweep grid of 100000 crank angles": ["sweep", "--samples", "100000", "--out", "sw"],
    "unreachable scheduler": ["sweep", "--scheduler", "tcp://10.255.255.1:8786", "--out", "sw"],
    "scheduler port out of range": ["sweep", "--scheduler", "tcp://127.0.0.1:99999", "--out", "sw"],
    "pole in synthesize function": ["synthesize", "function", "1/(x-2)", "--x", "1", "3", *FN],
    "tiny x range in synthesize function": ["synthesize", "function", "x**2", "--x", "1", "1.000001", *FN],
}


def _last(text: str) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return lines[-1][:300] if lines else ""


def plain(args: list[str], env: dict, cwd: Path) -> dict:
    r = timed_process([*RIGFEM, *args], env=env, cwd=cwd)
    return {"wall_s": r["wall_s"], "exit": r["exit"], "peak_tree_rss_mib": r["peak_tree_rss_mib"],
            "prints": _last(r["stderr_tail"]) or r["stdout_tail"].strip().split("\n")[0][:300],
            "files_left": sorted(os.listdir(cwd))}


def ctrl_c(env: dict, cwd: Path, after_s: float = 4.0) -> dict:
    """SIGINT during the meshing of a fine rail: seconds from the signal to the end."""
    p = subprocess.Popen([*RIGFEM, "mesh", "rail_size25", "--size", "2.5", "--out", "r.vtu"], env=env, cwd=cwd,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    time.sleep(after_s)
    t0 = time.perf_counter()
    p.send_signal(signal.SIGINT)
    err = p.communicate(timeout=120)[1]
    return {"wall_s": time.perf_counter() - t0, "exit": p.returncode, "prints": _last(err),
            "files_left": sorted(os.listdir(cwd))}


def cache_is_a_file(env: dict, cwd: Path) -> dict:
    (cwd / "cachefile").write_text("not a folder\n")
    r = plain(["cache"], {**env, "RIGFEM_CACHE": str(cwd / "cachefile")}, cwd)
    r["files_left"] = [f for f in r["files_left"] if f != "cachefile"]
    return r


def head(env: dict, cwd: Path) -> dict:
    cmd = " ".join([*RIGFEM, "kinematics", "--samples", "20000", "--json"]) + " | head -1 >/dev/null; echo ${PIPESTATUS[0]}"
    t0 = time.perf_counter()
    r = subprocess.run(["bash", "-c", cmd], env=env, cwd=cwd, capture_output=True, text=True)
    return {"wall_s": time.perf_counter() - t0, "exit": int(r.stdout.strip() or -1), "prints": _last(r.stderr) or "(nothing)",
            "files_left": sorted(os.listdir(cwd))}


def main() -> int:
    samples = {}
    for name, args in [*EXAMPLES.items(), ("Ctrl-C during meshing", None), ("cache folder is a file", None),
                       ("rigfem kinematics | head -1", None)]:
        with tempfile.TemporaryDirectory() as tmp:
            cwd = Path(tmp) / "work"
            cwd.mkdir()
            env = cold_env(Path(tmp) / "caches")
            row = (plain(args, env, cwd) if args is not None else ctrl_c(env, cwd) if name.startswith("Ctrl-C")
                   else cache_is_a_file(env, cwd) if name.startswith("cache") else head(env, cwd))
        row["command"] = ("rigfem " + " ".join(args)) if args is not None else {
            "Ctrl-C during meshing": "rigfem mesh rail_size25 --size 2.5 --out r.vtu, then Ctrl-C after 4 s",
            "cache folder is a file": "RIGFEM_CACHE=<a file> rigfem cache",
            "rigfem kinematics | head -1": "rigfem kinematics --samples 20000 --json | head -1"}[name]
        print(f"{name}: exit {row['exit']} in {row['wall_s']:.2f} s: {row['prints']}", flush=True)
        samples[name] = [row]
    slowest = max(r[0]["wall_s"] for r in samples.values())
    write_record("bad_inputs", samples, derived={"slowest_s": slowest,
                                                 "every_folder_empty": all(not r[0]["files_left"]
                                                                           for r in samples.values())})
    return 0


if __name__ == "__main__":
    sys.exit(main())
