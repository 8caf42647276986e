"""Issue 24's and issue 38's examples, tried as a new user would: what rigfem prints now and how
long it takes (wall time, exit code, peak memory of the process tree, the last line on stderr).

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
    # issue 38
    "mesh size 1e-300": ["mesh", "PF_4b_006", "--size", "1e-300", "--out", "p.vtu"],
    "mesh size 1e300": ["mesh", "PF_4b_006", "--size", "1e300", "--out", "p.vtu"],
    "rhombus (change point at 0 and 180 deg)": ["kinematics", "--four-bar", "500", "500", "500", "500", "--samples", "8"],
    "kite (reactions)": ["reactions", "--four-bar", "300", "700", "700", "300"],
    "250-character --csv": ["kinematics", "--samples", "8", "--csv", "k" * 246 + ".csv"],
    "260-character --csv": ["kinematics", "--samples", "8", "--csv", "k" * 256 + ".csv"],
}
#: examples run with something of the environment changed: (argv, extra environment, shell redirection)
SHELL = {
    "ASCII-only output encoding": (["--help"], {"PYTHONIOENCODING": "ascii"}, ""),
    "stdout closed": (["kinematics", "--samples", "8", "--csv", "k.csv"], {}, ">&-"),
    "file-size limit (ulimit -f 1024)": (["kinematics", "--samples", "100000", "--csv", "big.csv"], {}, "ulimit -f 1024;"),
    "cache folder inside --out": (["check", "--out", "res", "--force", "--fidelity", "draft", "--quiet"],
                                  {"RIGFEM_CACHE": "res/cache"}, "mkdir -p res/cache;"),
}


def _last(text: str) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return lines[-1][:300] if lines else ""


#: on success, the first line of the output naming one of these is what an example prints
TELLING = ("change points", "peak driver torque")


def plain(args: list[str], env: dict, cwd: Path) -> dict:
    r = timed_process([*RIGFEM, *args], env=env, cwd=cwd)
    out = r["stdout_tail"].strip().split("\n")
    return {"wall_s": r["wall_s"], "exit": r["exit"], "peak_tree_rss_mib": r["peak_tree_rss_mib"],
            "prints": _last(r["stderr_tail"]) or next((ln for ln in out if any(t in ln for t in TELLING)), out[0])[:300],
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


def shell(args: list[str], extra: dict, redirect: str, env: dict, cwd: Path) -> dict:
    """``args`` run by bash with ``redirect`` (a prefix ending in ';' or a redirection) and ``extra``."""
    pre, post = (redirect, "") if redirect.endswith(";") else ("", redirect)
    cmd = f"{pre} {' '.join([*RIGFEM, *args])} {post}; echo $? >&2"
    t0 = time.perf_counter()
    r = subprocess.run(["bash", "-c", cmd], env={**env, **extra}, cwd=cwd, capture_output=True, text=True)
    lines = [ln for ln in r.stderr.strip().splitlines() if ln.strip()]
    return {"wall_s": time.perf_counter() - t0, "exit": int(lines[-1]), "prints": _last("\n".join(lines[:-1])) or
            r.stdout.strip().split("\n")[0][:300], "files_left": sorted(os.listdir(cwd))}


def million(env: dict, cwd: Path) -> dict:
    """The largest valid kinematics output, its JSON thrown away: time and peak memory."""
    r = timed_process(["bash", "-c", " ".join([*RIGFEM, "kinematics", "--samples", "1000000", "--json"]) + " >/dev/null"],
                      env=env, cwd=cwd)
    return {"wall_s": r["wall_s"], "exit": r["exit"], "peak_tree_rss_mib": r["peak_tree_rss_mib"],
            "prints": _last(r["stderr_tail"]) or f"(the JSON; peak {r['peak_tree_rss_mib']:.0f} MiB)",
            "files_left": sorted(os.listdir(cwd))}


def big_scene(env: dict, cwd: Path) -> dict:
    with open(cwd / "big.toml", "wb") as fh:
        fh.truncate(4 * 2**30)   # sparse
    r = plain(["kinematics", "big.toml"], env, cwd)
    r["files_left"] = [f for f in r["files_left"] if f != "big.toml"]
    return r


def blank_reactions(env: dict, cwd: Path) -> dict:
    """final-cm's own reaction CSV with 359 of its 360 rows blank and marked singular."""
    subprocess.run([*RIGFEM, "reactions", "--csv", "r.csv"], env=env, cwd=cwd, capture_output=True, check=True)
    lines = (cwd / "r.csv").read_text().splitlines()
    head = [ln for ln in lines if ln.startswith(("#", "crank"))]
    rows = [ln for ln in lines if ln[:1].isdigit()]
    blank = [",".join([r.split(",")[0], *[""] * (r.count(",") - 1), "1"]) for r in rows[1:]]
    (cwd / "r.csv").write_text("\n".join(head + rows[:1] + blank) + "\n")
    (cwd / ".rigfem-outputs.json").unlink(missing_ok=True)
    r = plain(["check", "final-cm", "--reactions-csv", "r.csv", "--fidelity", "draft", "--quiet", "--out", "res"],
              env, cwd)
    r["files_left"] = [f for f in r["files_left"] if f != "r.csv"]
    return r


def head(env: dict, cwd: Path) -> dict:
    cmd = " ".join([*RIGFEM, "kinematics", "--samples", "20000", "--json"]) + " | head -1 >/dev/null; echo ${PIPESTATUS[0]}"
    t0 = time.perf_counter()
    r = subprocess.run(["bash", "-c", cmd], env=env, cwd=cwd, capture_output=True, text=True)
    return {"wall_s": time.perf_counter() - t0, "exit": int(r.stdout.strip() or -1), "prints": _last(r.stderr) or "(nothing)",
            "files_left": sorted(os.listdir(cwd))}


def main() -> int:
    samples = {}
    custom = {"Ctrl-C during meshing": (ctrl_c, "rigfem mesh rail_size25 --size 2.5 --out r.vtu, then Ctrl-C after 4 s"),
              "cache folder is a file": (cache_is_a_file, "RIGFEM_CACHE=<a file> rigfem cache"),
              "rigfem kinematics | head -1": (head, "rigfem kinematics --samples 20000 --json | head -1"),
              "4 GB scene file": (big_scene, "rigfem kinematics big.toml  # a sparse 4 GB file"),
              "a million angles as JSON": (million, "rigfem kinematics --samples 1000000 --json >/dev/null"),
              "359 of 360 reaction rows blank and singular":
                  (blank_reactions, "rigfem check final-cm --reactions-csv r.csv --fidelity draft --out res  "
                                    "# r.csv: rigfem reactions --csv, rows 2-360 blank, singular = 1")}
    for name in [*EXAMPLES, *custom, *SHELL]:
        with tempfile.TemporaryDirectory() as tmp:
            cwd = Path(tmp) / "work"
            cwd.mkdir()
            env = cold_env(Path(tmp) / "caches")
            if name in EXAMPLES:
                row = plain(EXAMPLES[name], env, cwd)
                row["command"] = "rigfem " + " ".join(a if len(a) < 60 else f"<{len(a)} characters>"
                                                      for a in EXAMPLES[name])
            elif name in custom:
                row, row["command"] = custom[name][0](env, cwd), custom[name][1]
            else:
                args, extra, redirect = SHELL[name]
                row = shell(args, extra, redirect, env, cwd)
                pre, post = (redirect, "") if redirect.endswith(";") else ("", redirect)
                row["command"] = " ".join(x for x in (pre, *(f"{k}={v}" for k, v in extra.items()), "rigfem",
                                                      *args, post) if x)
        print(f"{name}: exit {row['exit']} in {row['wall_s']:.2f} s: {row['prints']}", flush=True)
        samples[name] = [row]
    slowest = max(r[0]["wall_s"] for r in samples.values())
    write_record("bad_inputs", samples, derived={"slowest_s": slowest,
                                                 "every_folder_empty": all(not r[0]["files_left"]
                                                                           for r in samples.values())})
    return 0


if __name__ == "__main__":
    sys.exit(main())
