"""Compare two rigfem result folders (or report.json files) number by number.

Used to show that a change moves no result: every numeric leaf of report.json must agree
within ``--rtol`` (relative, with an absolute floor ``--atol`` for values near zero).
Timings, versions, paths and dates are ignored.

    python benchmarks/compare_reports.py OLD_DIR NEW_DIR --rtol 1e-12
"""

import argparse
import json
import math
import sys
from pathlib import Path

#: keys whose values legitimately differ between runs
IGNORED = {"seconds", "version", "generated", "command", "cache", "load_avg", "wall_s", "cpu_s", "out", "files"}


def leaves(obj, path=""):
    """(path, number) for every numeric leaf, skipping IGNORED keys."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k not in IGNORED:
                yield from leaves(v, f"{path}.{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from leaves(v, f"{path}[{i}]")
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        yield path, float(obj)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rtol", type=float, default=1e-12)
    ap.add_argument("--atol", type=float, default=1e-9)
    a = ap.parse_args(argv)
    load = lambda p: json.loads((Path(p) / "report.json" if Path(p).is_dir() else Path(p)).read_text())
    old, new = dict(leaves(load(a.old))), dict(leaves(load(a.new)))
    missing = sorted(set(old) ^ set(new))
    worst, bad = 0.0, []
    for k in sorted(set(old) & set(new)):
        d = abs(old[k] - new[k])
        rel = d / max(abs(old[k]), abs(new[k])) if d > a.atol else 0.0
        worst = max(worst, rel)
        if not math.isclose(old[k], new[k], rel_tol=a.rtol, abs_tol=a.atol):
            bad.append(f"{k}: {old[k]!r} -> {new[k]!r}")
    print(f"{len(set(old) & set(new))} numbers compared, largest relative difference {worst:.3g}, "
          f"{len(bad)} outside rtol {a.rtol:g}, {len(missing)} only in one report")
    for line in (bad + [f"only in one: {m}" for m in missing])[:20]:
        print("  " + line)
    return 0 if not bad and not missing else 1


if __name__ == "__main__":
    sys.exit(main())
