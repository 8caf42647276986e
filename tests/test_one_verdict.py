"""One verdict stage for every path: the sweep judges a configuration as ``rigfem check`` does.

For configurations drawn from the sweep (passing, failing, undecided, near the limit), the check's
own stages on the same mesh (the sweep's unit bases refine every hole a coupling may use; the
check is given that mesh) give the same verdict, utilisation and error band per part case as the
sweep's superposition judged by the same verdict stage.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rigfem.dynamics import peaks, simulate
from rigfem.fe.executor import Plan, solve_cases
from rigfem.linkage import four_bar
from rigfem.loads import part_cases
from rigfem.sweep import SweepParams, build_bases, enumerate_configs, evaluate
from rigfem.sweep.bases import _geometries
from rigfem.verdict.part import judge

#: coarse linear meshes and three parts (a rail, a plate, the post) keep it quick
CHECK = (("order", 1), ("size_mm", 14.0), ("local_size_mm", 7.0), ("bearing_directions", 4),
         ("parts", ("crank_rail", "plate_A", "post_B")))
N = 20


@pytest.fixture(scope="module")
def sweep():
    p = SweepParams(check=CHECK)
    return p, build_bases(p)


def _drawn(p: SweepParams, bases) -> list[tuple[dict, dict]]:
    """``N`` configurations the sweep computes, with every verdict it gives represented: the
    failing and undecided ones found among a seeded random draw, the rest passing, the two nearest
    the limit among them."""
    configs = enumerate_configs(p)
    rows = []
    for i in np.random.default_rng(3).permutation(len(configs))[:1500]:
        row = evaluate(configs[i], p, bases)
        if row["status"] == "ok":
            rows.append((configs[i], row))
    by = {v: [r for r in rows if r[1]["verdict"] == v] for v in ("pass", "fail", "undecided")}
    near = sorted(by["pass"], key=lambda r: -r[1]["max_util_pct"])[:2]
    picked = by["fail"][:4] + by["undecided"][:6] + near
    picked += [r for r in by["pass"] if r not in picked][: N - len(picked)]
    assert len(picked) == N and all(by[v] for v in by), {v: len(r) for v, r in by.items()}
    return picked


@pytest.mark.heavy  # 20 configurations' FE solves on the sweep's meshes (~1 min)
def test_the_sweep_judges_as_the_check_on_the_same_mesh(sweep):
    p, bases = sweep
    s = p.settings()
    by_geo, merged, _ = _geometries(p)
    for cfg, row in _drawn(p, bases):
        h = simulate(four_bar(**cfg, rails_mm=p.rails))
        cases = [(m, dataclasses.replace(c, refine=merged[(c.part, tuple(sorted(c.params.items())))].refine))
                 for m, c in part_cases(h, peaks(h), s)]  # the check's cases, on the sweep's mesh
        results = solve_cases(cases, s, Plan(frames=0))
        verdicts = judge([r.outcome for r in results], s)
        assert row["verdict"] == verdicts.stress, cfg
        for pv in verdicts.parts:
            o, v = pv.outcome, pv.verdict
            key = f"{o.name}_{o.mode}"
            # float32 unit fields; original mode splits the peak force over the two nearest of 72 directions
            assert row[f"{key}_util_pct"] == pytest.approx(v.utilisation_pct, rel=2e-3, abs=1e-6), (cfg, key)
            assert row[f"{key}_band_pct"] == pytest.approx(v.error_pct, rel=2e-3, abs=1e-3), (cfg, key)
