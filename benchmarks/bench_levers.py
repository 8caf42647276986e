"""Issue 26's other levers: ``rigfem check`` cold and warm before and after, and the peaks they move.

Run from the repository root, once per source tree (one check at a time; the record is merged):

    git archive <base> | tar -x -C /tmp/base
    python benchmarks/bench_levers.py --label before --src /tmp/base
    python benchmarks/bench_levers.py --label after

-> results/benchmarks/levers.json (``python benchmarks/publish.py`` writes levers.md).  Each run is
a separate process (``python -m rigfem check``, imported from ``--src``) on a fresh rigfem and
numba cache (cold), then again on the cache it filled (warm), and warm with ``--no-pictures``
where the tree has it; wall time and peak RSS of the process tree (benchmarks/record.py).  The
peak of every part case of each label is kept, and its relative change against ``before``.
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

from record import OUT, ROOT, cold_env, timed_process, write_record

NAME = "levers"


def _check(src: Path, env: dict, out: Path, fidelity: str, scene: str, extra: list[str]) -> tuple[dict, dict]:
    r = timed_process([sys.executable, "-m", "rigfem", "check", scene, "--fidelity", fidelity, "--quiet",
                       "--out", str(out), *extra], env={**env, "PYTHONPATH": str(src)}, cwd=src)
    if r["exit"] not in (0, 1):
        raise SystemExit(f"rigfem check failed ({r['exit']}): {r['stderr_tail']}")
    rep = json.loads((out / "report.json").read_text())
    peaks = {f"{p['name']} {p['mode']}": p["peak_mpa"] for p in rep["parts"]}
    return {k: r[k] for k in ("wall_s", "peak_tree_rss_mib", "exit", "load_before", "load_after")}, peaks


def _has_no_pictures(src: Path) -> bool:
    return "--no-pictures" in (src / "rigfem" / "cli" / "check.py").read_text()


def _commit(src: Path) -> str:
    r = subprocess.run(["git", "-C", str(src), "rev-parse", "HEAD"], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else f"source tree {src} (git archive of the base)"


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--label", required=True, help="before | after | a lever's name")
    ap.add_argument("--src", type=Path, default=ROOT, help="the source tree to run (default this repository)")
    ap.add_argument("--fidelity", default="standard")
    ap.add_argument("--scene", default="final-cm")
    a = ap.parse_args(argv)
    old = json.loads((OUT / f"{NAME}.json").read_text()) if (OUT / f"{NAME}.json").is_file() else {}
    samples, derived, params = old.get("samples", {}), old.get("derived", {}), old.get("params", {})
    peaks = derived.get("peaks_mpa", {})
    with tempfile.TemporaryDirectory() as tmp:
        env = cold_env(tmp)
        runs = [("cold", []), ("warm", [])] + ([("warm, --no-pictures", ["--no-pictures"])]
                                               if _has_no_pictures(a.src) else [])
        for i, (what, extra) in enumerate(runs):
            sample, peak = _check(a.src.resolve(), env, Path(tmp) / f"out{i}", a.fidelity, a.scene, extra)
            samples[f"{a.label} {what}"] = [sample]
            peaks[a.label] = peak
            print(f"{a.label} {what}: {sample['wall_s']:.1f} s, {sample['peak_tree_rss_mib']:.0f} MiB")
    derived["peaks_mpa"] = peaks
    if "before" in peaks:
        derived["peak change vs before"] = {
            label: {k: abs(v / peaks["before"][k] - 1) for k, v in p.items() if peaks["before"].get(k)}
            for label, p in peaks.items() if label != "before"}
    params.setdefault("runs", {})[a.label] = {"command": shlex.join(["python", *sys.argv]),
                                              "source": _commit(a.src.resolve())}
    params.update(fidelity=a.fidelity, scene=a.scene)
    print(f"wrote {write_record(NAME, samples, derived, params)}")


if __name__ == "__main__":
    main()
