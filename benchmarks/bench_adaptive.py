"""Verdict-driven refinement against fixed preset meshes: per part, DOF, seconds, peak, band, verdict.

Run: ``python benchmarks/bench_adaptive.py [--fidelity standard draft] [--scene final-cm]``
-> results/benchmarks/adaptive.json (then ``python benchmarks/publish.py`` writes adaptive.md).
For each preset, two cold ``rigfem check`` processes (each its own empty caches), one after the
other: *before* meshes every part at the preset (``--no-adaptive``), *after* lets each part climb
the ladder (rigfem.settings.LADDER) only until it is decided within the preset's target.  Per part
geometry the seconds are its mesh, assembly and solves (every level it tried, for *after*).
Accuracy: every *after* verdict must equal *before*'s, and ``|after − before| ≤ both bands`` (MPa);
at the scene's committed fidelity the peaks are also compared with its committed report.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from record import cold_env, timed_process, write_record

ROOT = Path(__file__).resolve().parents[1]


def _check(scene: str, fidelity: str, adaptive: bool) -> tuple[dict, dict]:
    """One cold ``rigfem check`` process: its timing (record.timed_process) and its report."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "rigfem", "check", scene, "--fidelity", fidelity, "--frames", "0",
               "--out", str(Path(tmp) / "o"), "--quiet"] + ([] if adaptive else ["--no-adaptive"])
        run = timed_process(cmd, env=cold_env(tmp))
        if run["exit"] not in (0, 1):
            raise SystemExit(f"rigfem check failed ({run['exit']}): {run['stderr_tail']}")
        return run, json.loads((Path(tmp) / "o" / "report.json").read_text())


def _part_seconds(p: dict) -> float:
    """Mesh, assembly and solve seconds of a part entry's geometry (every ladder level)."""
    return float(sum(s["seconds"] for s in p["mesh"]["ladder"]))


def _rows(fid: str, before: dict, after: dict) -> list[dict]:
    """One flat row per part case: before and after side by side, and the accuracy test."""
    out = []
    for b, a in zip(before["parts"], after["parts"]):
        band = lambda p: p["peak_mpa"] * p["error_pct"] / 100  # noqa: E731
        out.append({"fidelity": fid, "part": b["name"], "mode": b["mode"],
                    "before_dofs": b["mesh"]["dofs"], "after_dofs": a["mesh"]["dofs"],
                    "after_ladder_dofs": sum(s["dofs"] for s in a["mesh"]["ladder"]),
                    "after_level": a["mesh"]["level"], "after_stopped": a["mesh"]["stopped"],
                    "before_s": _part_seconds(b), "after_s": _part_seconds(a),
                    "before_peak_mpa": b["peak_mpa"], "after_peak_mpa": a["peak_mpa"],
                    "before_band_mpa": band(b), "after_band_mpa": band(a),
                    "before_verdict": b["verdict"], "after_verdict": a["verdict"],
                    "consistent": abs(a["peak_mpa"] - b["peak_mpa"]) <= band(a) + band(b)
                    and a["verdict"] == b["verdict"]})
    return out


def _committed(scene: str, after: dict) -> list[dict]:
    """The adaptive peaks against the scene's committed report (results/<scene>/report.json)."""
    old = json.loads((ROOT / "results" / scene / "report.json").read_text())
    out = []
    for o, a in zip(old["parts"], after["parts"]):
        bo, ba = o["peak_mpa"] * o["error_pct"] / 100, a["peak_mpa"] * a["error_pct"] / 100
        out.append({"part": o["name"], "mode": o["mode"], "committed_peak_mpa": o["peak_mpa"],
                    "after_peak_mpa": a["peak_mpa"], "difference_mpa": a["peak_mpa"] - o["peak_mpa"],
                    "bands_mpa": bo + ba, "consistent": abs(a["peak_mpa"] - o["peak_mpa"]) <= bo + ba
                    and o["verdict"] == a["verdict"]})
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fidelity", nargs="+", default=["standard", "draft"])
    ap.add_argument("--scene", default="final-cm")
    args = ap.parse_args(argv)
    samples, derived, committed = {"parts": [], "committed": []}, {}, None
    for fid in args.fidelity:
        (tb, before), (ta, after) = _check(args.scene, fid, False), _check(args.scene, fid, True)
        samples[f"{fid} before"], samples[f"{fid} after"] = [tb], [ta]
        samples["parts"] += _rows(fid, before, after)
        derived[f"{fid}: wall after / before"] = ta["wall_s"] / tb["wall_s"]
        derived[f"{fid}: peak RSS after / before"] = ta["peak_tree_rss_mib"] / tb["peak_tree_rss_mib"]
        if committed is None and (ROOT / "results" / args.scene / "report.json").is_file():
            old = json.loads((ROOT / "results" / args.scene / "report.json").read_text())
            if old["settings"]["fidelity"] == fid:
                committed = samples["committed"] = _committed(args.scene, after)
    derived["every part consistent"] = float(all(r["consistent"] for r in samples["parts"] + samples["committed"]))
    samples = {k: v for k, v in samples.items() if v}  # no committed comparison at another fidelity
    path = write_record("adaptive", samples, derived, params={"scene": args.scene, "fidelity": args.fidelity})
    print(path)


if __name__ == "__main__":
    main()
