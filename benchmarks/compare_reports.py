"""Compare two rigfem result folders (or report.json files, or sweep tables) number by number.

Used to show that a change moves no result: every numeric leaf of report.json must agree
within ``--rtol`` (relative, with an absolute floor ``--atol`` for values near zero).
Timings, versions, paths and dates are ignored.  A sweep table (.csv or .csv.gz) compares
every number of the configurations computed (status ok), keyed by their lengths; ``--only
SUFFIX`` keeps the columns ending so (e.g. ``_mpa``: the part peaks).

    python benchmarks/compare_reports.py OLD_DIR NEW_DIR --rtol 1e-12
    git show c1d9a40:results/sweep/sweep_four-bar.csv.gz > /tmp/old.csv.gz
    python benchmarks/compare_reports.py /tmp/old.csv.gz results/sweep/sweep_four-bar.csv.gz --only _mpa --rtol 1e-3
    python benchmarks/compare_reports.py results/final-cm NEW_DIR --bands   # a change of mesh or solver

``--bands`` compares what a verdict rests on instead (:func:`band_problems`): each part's
verdict unchanged and its peak within the error bands of both reports.
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


def table_leaves(path: str):
    """(lengths.column, number) for every finite number of the computed rows of a sweep table."""
    import pandas as pd

    from rigfem.sweep.configs import LENGTHS

    t = pd.read_csv(path, keep_default_na=False, na_values=[""])
    t = t[t["status"] == "ok"]
    keys = LENGTHS[t["type"].iloc[0]]
    for _, row in t.iterrows():
        name = "[" + ", ".join(f"{row[k]:g}" for k in keys) + "]"
        for col, v in row.items():
            if col not in keys and isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
                yield f"{name}.{col}", float(v)


def _load(path: str) -> dict:
    if path.endswith((".csv", ".csv.gz")):
        return dict(table_leaves(path))
    p = Path(path)
    return dict(leaves(json.loads((p / "report.json" if p.is_dir() else p).read_text())))


def band_problems(old: dict, new: dict) -> list[str]:
    """Parts of report ``new`` whose verdict differs from report ``old``'s, or whose peak band misses it.

    A peak's band is peak ± peak·error_pct/100 (the report's error estimate); the two bands must
    overlap: |new − old| ≤ old·e_old + new·e_new.  Every part case of ``new`` must be in ``old``
    (``new`` may check fewer parts).
    """
    ref = {(p["name"], p["mode"]): p for p in old["parts"]}
    out = []
    for p in new["parts"]:
        o, key = ref.get((p["name"], p["mode"])), f"{p['name']} {p['mode']}"
        if o is None:
            out.append(f"{key}: not in the reference report")
            continue
        if p["verdict"] != o["verdict"]:
            out.append(f"{key}: verdict {o['verdict']} -> {p['verdict']}")
        if (p.get("peak_mpa") is None) != (o.get("peak_mpa") is None):
            out.append(f"{key}: peak {o.get('peak_mpa')} -> {p.get('peak_mpa')}")
        elif p.get("peak_mpa") is not None:
            gap = abs(p["peak_mpa"] - o["peak_mpa"])
            room = o["peak_mpa"] * o["error_pct"] / 100 + p["peak_mpa"] * p["error_pct"] / 100
            if not gap <= room:
                out.append(f"{key}: peak {o['peak_mpa']:.2f} ± {o['error_pct']:.1f} % -> {p['peak_mpa']:.2f} ± "
                           f"{p['error_pct']:.1f} % MPa: the bands do not overlap")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rtol", type=float, default=1e-12)
    ap.add_argument("--atol", type=float, default=1e-9)
    ap.add_argument("--only", metavar="SUFFIX", help="compare only the numbers whose key ends with SUFFIX")
    ap.add_argument("--bands", action="store_true", help="compare verdicts and peak error bands (reports only)")
    a = ap.parse_args(argv)
    if a.bands:
        old, new = (json.loads((Path(x) / "report.json" if Path(x).is_dir() else Path(x)).read_text())
                    for x in (a.old, a.new))
        bad = band_problems(old, new)
        print(f"{len(new['parts'])} part cases compared, {len(bad)} outside the rule")
        print("\n".join("  " + b for b in bad))
        return 1 if bad else 0
    old, new = _load(a.old), _load(a.new)
    if a.only:
        old, new = ({k: v for k, v in d.items() if k.endswith(a.only)} for d in (old, new))
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
