"""Independent verification of a scene: every part case of ``rigfem check`` re-solved by CalculiX.

The critical load combination (crank angle) of each part case is exported with the same mesh,
supports and nodal loads, solved by ccx, and the peak von Mises and displacement compared.
Writes results/benchmarks/calculix_verify_<scene>.{json,md}.

    python benchmarks/verify_calculix.py final-cm --fidelity draft --threads 1
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from rigfem.calculix import verify_scene

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="final-cm")
    ap.add_argument("--fidelity", default="draft", help="draft | standard | fine")
    ap.add_argument("--threads", type=int, default=1, help="ccx threads")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows = verify_scene(args.scene, {"fidelity": args.fidelity}, threads=args.threads)
    info = {"scene": args.scene, "fidelity": args.fidelity, "ccx_threads": args.threads,
            "seconds": time.perf_counter() - t0, "cases": rows,
            "command": "python benchmarks/verify_calculix.py " + " ".join(argv if argv is not None else sys.argv[1:])}
    lines = [f"# rigfem vs CalculiX 2.20: scene {args.scene} ({args.fidelity})", "",
             f"Command: `{info['command']}` ({info['seconds']:.0f} s)  ",
             "Each part case's critical load combination, same mesh/supports/loads, solved by ccx.", "",
             "| part | mode | DOF | peak σvm rigfem [MPa] | ccx [MPa] | Δ peak | max Δu / max u |",
             "|---|---|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['part']} | {r['mode']} | {r['dof']} | {r['peak_von_mises']:.3f} | {r['peak_von_mises_ccx']:.3f} "
              f"| {100 * r['peak_rel_diff']:+.4f} % | {100 * r['displacement_rel_diff']:.4f} % |" for r in rows]
    if rows:
        worst = max(abs(r["peak_rel_diff"]) for r in rows)
        lines += ["", f"Largest peak difference {100 * worst:.4f} % (the .frd holds 5 significant digits)."]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / f"calculix_verify_{args.scene}.json").write_text(json.dumps(info, indent=2) + "\n")
    (OUT / f"calculix_verify_{args.scene}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
