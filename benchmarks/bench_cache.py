"""What each kind of cache entry saves a warm run, and what it costs on disk.

    python benchmarks/bench_cache.py --repeats 3

One cache is filled by a cold run of each workload; then each workload runs warm with every kind
kept, and once per kind with that kind left out (:meth:`rigfem.cache.Cache.without`: computed, not
stored, not read), each in a fresh process.  The time a kind saves is the warm run without it
minus the warm run with everything (medians of ``--repeats`` runs, side by side in one run); its
disk is the size of its entries after the cold runs.  The record is
``results/benchmarks/cache_kinds.json``; ``benchmarks/publish.py`` renders the table.

Workloads (each the kinds it reads): ``rigfem check final-cm`` standard (meshes, kernels,
straightened, body_resultants, solutions, sweeps, ladders, pictures, viewer), ``rigfem parts``
(volumes), ``rigfem kinematics`` of a scene (scenes) and the unit bases of ``synthesize --rig``
(bases).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
from pathlib import Path

from record import ROOT, cold_env, timed_process, write_record

#: workload -> (python code run in a fresh process with the cache CACHE not keeping OFF, the kinds it reads)
WORKLOADS = {
    "check": ("from rigfem.pipeline import run_check, Output; "
              "run_check('final-cm', Output(OUT, force=True), CTX)",
              ("meshes", "kernels", "straightened", "body_resultants", "solutions", "sweeps", "ladders",
               "pictures", "viewer")),
    "parts": ("from rigfem import rig; from rigfem.mesh.volume import mass_kg; "
              "[mass_kg(rig.load_part(n), CACHE) for n in rig.known_parts()]", ("volumes",)),
    "kinematics": ("from rigfem.scene import load_scene; load_scene('mech2-fourbar-coupler-point', CACHE)",
                   ("scenes",)),
    "bases": ("from rigfem.sweep import SweepParams, build_bases; build_bases(SweepParams(), cache=CACHE)",
              ("bases",)),
}

_PRELUDE = ("import pathlib, sys; from rigfem.cache import Cache; from rigfem.context import Context; "
            "CACHE = Cache(pathlib.Path(sys.argv[1]), 10**12, frozenset(sys.argv[2].split(',')) - {''}); "
            "CTX = Context(CACHE); OUT = pathlib.Path(sys.argv[3]); ")


def run(workload: str, root: Path, off: str, out: Path, env: dict) -> dict:
    code, _ = WORKLOADS[workload]
    r = timed_process([sys.executable, "-c", _PRELUDE + code, str(root), off, str(out)], env=env, cwd=ROOT)
    if r["exit"]:
        raise SystemExit(f"{workload} (without {off or 'nothing'}) failed: {r['stderr_tail']}")
    return {"wall_s": r["wall_s"], "peak_tree_rss_mib": r["peak_tree_rss_mib"], "load": r["load_before"][0]}


def disk(root: Path) -> dict[str, int]:
    """Bytes of each kind's entries."""
    from rigfem.cache import Cache

    sizes: dict[str, int] = {}
    for folder, size, _ in Cache(root, 10**12).entries():
        sizes[folder.parent.name] = sizes.get(folder.parent.name, 0) + size
    return sizes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--workloads", nargs="+", default=list(WORKLOADS), choices=list(WORKLOADS))
    a = ap.parse_args()
    samples, derived = {}, {"kinds": {}}
    with tempfile.TemporaryDirectory(prefix="rigfem-bench-cache-") as tmp:
        tmp = Path(tmp)
        env, root = cold_env(tmp), tmp / "cache"
        for w in a.workloads:
            samples[f"{w} cold"] = [run(w, root, "", tmp / "out", env)]
            for _ in range(a.repeats):
                samples.setdefault(f"{w} warm", []).append(run(w, root, "", tmp / "out", env))
                for kind in WORKLOADS[w][1]:
                    samples.setdefault(f"{w} warm without {kind}", []).append(run(w, root, kind, tmp / "out", env))
        sizes = disk(root)
    for w in a.workloads:
        warm = statistics.median(s["wall_s"] for s in samples[f"{w} warm"])
        for kind in WORKLOADS[w][1]:
            without = statistics.median(s["wall_s"] for s in samples[f"{w} warm without {kind}"])
            derived["kinds"][kind] = {"workload": w, "saved_s": without - warm, "warm_s": warm,
                                      "without_s": without, "disk_bytes": sizes.get(kind, 0)}
    path = write_record("cache_kinds", samples, derived, params={"repeats": a.repeats, "workloads": a.workloads})
    print(json.dumps(derived, indent=1))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
