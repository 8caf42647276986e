"""Dated, machine-readable benchmark records: the one place every benchmark writes its figures.

A record (``results/benchmarks/<name>.json``) holds the date (UTC), the commit, the machine,
the load average, the exact command, the raw samples and the summaries computed from them;
``benchmarks/publish.py`` renders the tables and README's figures from the records only.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import shlex
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "benchmarks"
PACKAGES = ("numpy", "scipy", "scikit-fem", "gmsh", "numba", "pypardiso", "dask", "distributed", "pyvista")
#: the keys every record must carry (tests/test_figures.py checks them)
REQUIRED = ("name", "date", "commit", "machine", "load", "command", "samples", "summary", "derived")


def machine() -> dict:
    """Cores, CPU model, memory (GiB), platform, Python and key package versions."""
    cpu = next((ln.split(":", 1)[1].strip() for ln in _read("/proc/cpuinfo").splitlines()
                if ln.startswith("model name")), platform.processor())
    mem = next((int(ln.split()[1]) / 2**20 for ln in _read("/proc/meminfo").splitlines()
                if ln.startswith("MemTotal:")), float("nan"))
    versions = {}
    for pkg in PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = None
    return {"cores": os.cpu_count(), "cpu": cpu, "memory_gib": round(mem, 2), "platform": platform.platform(),
            "python": platform.python_version(), "packages": versions}


def _read(path: str) -> str:
    try:
        return Path(path).read_text()
    except OSError:
        return ""


def commit() -> dict:
    """git HEAD of the repository and whether its tracked files outside results/ differ from it: a
    record measures the code, and a benchmark that writes its record as it goes (bench_perf.py, after
    every row) must not call its own output a modified tree."""
    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True).stdout.strip()
    return {"sha": git("rev-parse", "HEAD"),
            "dirty": bool(git("status", "--porcelain", "--untracked-files=no", "--", ".", ":(exclude)results"))}


def command_line() -> str:
    """The command that runs this benchmark, as typed from the repository root."""
    script = Path(sys.argv[0]).resolve()
    try:
        script = script.relative_to(ROOT)
    except ValueError:
        pass
    return shlex.join(["python", str(script), *sys.argv[1:]])


def cold_env(tmp: str | Path, **extra: str) -> dict:
    """Environment of a cold run: empty rigfem cache and empty numba cache under ``tmp``; Python's
    bytecode as a user has it (written and reused: a regular ``pip install`` compiles it at install),
    whatever the calling shell says (``PYTHONDONTWRITEBYTECODE`` would recompile rigfem every run)."""
    tmp = Path(tmp)
    base = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return {**base, "RIGFEM_CACHE": str(tmp / "rigfem-cache"), "NUMBA_CACHE_DIR": str(tmp / "numba-cache"),
            **extra}


def timed_process(cmd: list[str], env: dict | None = None, cwd: str | Path | None = None,
                  poll_s: float = 0.05) -> dict:
    """Run ``cmd`` as its own process; wall time, peak RSS of its whole process tree, load average.

    The tree's RSS is the sum over the live process and its descendants, polled every ``poll_s``
    (pages shared between a parent and its forked children count once per process).  The wall
    time ends when the process does (a thread waits for it), not at the next poll: polling alone
    added up to ``poll_s`` (0–50 ms) to every run, a sixth of a light command's time.
    """
    import psutil

    load0 = os.getloadavg()
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        p = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=out, stderr=err, text=True)
        root, peak = psutil.Process(p.pid), 0  # before the waiter can reap the process
        ended: list[float] = []
        waiter = threading.Thread(target=lambda: (p.wait(), ended.append(time.perf_counter())), daemon=True)
        waiter.start()
        while waiter.is_alive():
            rss = 0
            try:
                procs = [root, *root.children(recursive=True)]
            except psutil.NoSuchProcess:
                procs = []
            for q in procs:
                try:
                    rss += q.memory_info().rss
                except psutil.NoSuchProcess:
                    pass
            peak = max(peak, rss)
            waiter.join(poll_s)
        wall = ended[0] - t0
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    return {"wall_s": wall, "peak_tree_rss_mib": peak / 2**20, "exit": p.returncode,
            "load_before": list(load0), "load_after": list(os.getloadavg()),
            "stdout_tail": stdout[-2000:], "stderr_tail": stderr[-400:] if p.returncode else ""}


def summarise(samples: dict[str, list]) -> dict:
    """Median, min, max and count of every numeric field of every series of samples."""
    out = {}
    for series, rows in samples.items():
        rows = [r if isinstance(r, dict) else {"value": r} for r in rows]
        fields = [k for k in (rows[0] if rows else {}) if all(_number(r.get(k)) for r in rows)]
        out[series] = {k: {"median": statistics.median(r[k] for r in rows), "min": min(r[k] for r in rows),
                           "max": max(r[k] for r in rows), "n": len(rows)} for k in fields}
    return out


def _number(x: object) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and x == x and abs(x) != float("inf")


def write_record(name: str, samples: dict[str, list], derived: dict | None = None, params: dict | None = None,
                 command: str | None = None, out: Path = OUT) -> Path:
    """``results/benchmarks/<name>.json``: date, commit, machine, load, command, raw samples, summaries.

    ``samples`` maps a series name to its raw samples (numbers or flat dicts); ``derived`` holds the
    figures computed from them (ratios, efficiencies); ``params`` the run's settings.
    """
    rec = {"name": name, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "commit": commit(), "machine": machine(), "load": list(os.getloadavg()),
           "command": command or command_line(), "params": params or {}, "samples": samples,
           "summary": summarise(samples), "derived": derived or {}}
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(rec, indent=1, default=float) + "\n")
    tmp.replace(path)
    return path


def read_record(name: str, out: Path = OUT) -> dict:
    """The record ``results/benchmarks/<name>.json``."""
    return json.loads((out / f"{name}.json").read_text())
