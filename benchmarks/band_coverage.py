"""Coverage of the peaks' error band per preset, and its calibration (issue 22 §4).

Solves the closed-form cases (Lamé cylinder, plate with a hole, beam in bending; P1 and P2, at each
preset's sizes and at calibration sizes) and reads the reference parts' committed convergence
sequences (results/convergence/<part>.json).  Writes results/convergence/band_coverage.json (every
raw case) and band_coverage.md (coverage per preset, before and after calibration).  About a minute.

    python benchmarks/band_coverage.py
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from rigfem.verification.band_coverage import markdown, run

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "convergence"


def main() -> None:
    t0 = time.perf_counter()
    rec = run(OUT)
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "unknown"
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "rigfem"], capture_output=True,
                           text=True).stdout.strip()
    rec = {"date_utc": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
           "commit": commit + (" (+ uncommitted changes in rigfem/)" if dirty else ""),
           "machine": f"{platform.node()}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}",
           "command": "python benchmarks/band_coverage.py", "seconds": round(time.perf_counter() - t0, 1), **rec}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "band_coverage.json").write_text(json.dumps(rec, indent=1) + "\n")
    (OUT / "band_coverage.md").write_text(markdown(rec))
    print(markdown(rec))


if __name__ == "__main__":
    sys.exit(main())
