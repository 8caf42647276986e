"""NAFEMS LE10 (thick plate under pressure): σyy at D against the published −5.38 MPa, and CalculiX.

Tolerances: NAFEMS asks for σyy(D) within 2 % of −5.38 MPa.  The "standard-like" mesh here is
the 150 mm one (4 element layers through the 600 mm thickness, about 30k DOF, seconds): it
reads −5.43 MPa (+0.9 %).  The P2 answer at D is not monotonic on the coarse levels (400 / 283 /
200 mm: +2.1 / −0.4 / +2.3 %, 300 mm: +1.3 %; results/benchmarks/le10.md), so the coarse 300 mm
mesh used for the cross-checks is held to a looser 3 %; its real checks are CalculiX on the
identical model (the .frd keeps 5 digits: 2e-4) and the load balance (p × area to 1e-4: the
curved P2 faces carry the exact ellipse area to about 1e-5).
"""

from __future__ import annotations

import numpy as np
import pytest

from rigfem.io import export_model, run_ccx
from rigfem.mesh import PartMesh
from rigfem.verification.le10 import (
    INNER,
    OUTER,
    PRESSURE,
    TARGET_SYY,
    le10_mesh,
    load,
    solve_le10,
    supports,
)


@pytest.fixture(scope="module")
def coarse():
    return solve_le10(le10_mesh(300.0))


def test_standard_like_mesh_within_two_percent():
    r = solve_le10(le10_mesh(150.0))
    assert r["syy_D"] == pytest.approx(TARGET_SYY, rel=0.02)


def test_coarse_mesh_and_load_balance(coarse):
    assert coarse["syy_D"] == pytest.approx(TARGET_SYY, rel=0.03)
    sol = coarse["solution"]
    # the supports carry the whole pressure resultant: p × area of the quarter elliptic annulus
    area = np.pi / 4 * (OUTER[0] * OUTER[1] - INNER[0] * INNER[1])
    fz = sum(r[0, 2] for r in sol.support_reactions.values())
    assert fz == pytest.approx(PRESSURE * area, rel=1e-4)
    assert sol.equilibrium_error[0] < 1e-10


def test_units_do_not_matter(coarse):
    """The same mesh in metres (E and p in N/m²) gives the same σyy(D) in MPa."""
    pm = coarse["model"].part
    metres = PartMesh(pm.name, pm.points / 1000.0, pm.tets, pm.surfaces, {},
                      curved_edges=pm.curved_edges, curved_points=pm.curved_points / 1000.0)
    assert solve_le10(metres, unit_mm=1000.0)["syy_D"] == pytest.approx(coarse["syy_D"], rel=1e-8)


@pytest.mark.tool("ccx")
def test_calculix_on_the_same_mesh(coarse, tmp_path):
    deck = export_model(coarse["model"], supports(), [load()], tmp_path / "le10.inp", heading="NAFEMS LE10")
    res = run_ccx(deck)
    syy_ccx = res.stress[0, coarse["node_D"], 1]
    assert syy_ccx == pytest.approx(coarse["syy_D"], rel=2e-4)
    u = coarse["solution"].displacement()
    assert np.abs(res.displacement[0, :len(u)] - u).max() < 2e-4 * np.abs(u).max()
