"""Issue 6, stability at the extremes — FE.

Already covered elsewhere (not duplicated here):
* loads 1e-6 … 1e6 N, displacements linear to 1e-8 — test_fe_cantilever::test_linearity_over_twelve_decades
* mm–N–MPa vs m–N–Pa on the solver — test_fe_cantilever::test_unit_system_invariance
* missing / insufficient supports — test_fe_cantilever::test_missing_or_insufficient_supports_raise
* memory guard refuses a 0.1 mm rail — test_mesh::test_memory_guard_refuses_before_meshing
* finite() refuses NaN/inf — test_report::test_finite_refuses_nan_and_inf_and_names_the_field

Here: what the report reads off a solution (peak, error estimate) over twelve decades of load,
one-cell meshes, the guard's message and that it acts before gmsh meshes, aspect ratio 100
(slender bar, thin plate) against Euler–Bernoulli with the backward error checked, ν → 0.5
(P1 locking), the residual check on every solve, and Pa values in a mm scene.
"""

import warnings

import numpy as np
import pytest
from fe_shapes import box

from rigfem.cache import NO_CACHE
from rigfem.errors import InputError
from rigfem.fe import Fixed, SolverError, SurfaceForce, Symmetry, build_model, solve
from rigfem.material import Material, get_material, material_from_dict
from rigfem.report import finite

STEEL = get_material("rig_steel")


def _cantilever(L, B, H, n, order, mat=STEEL, plane_strain=False, cases=((0, 0, -1.0),)):
    """Box cantilever clamped at x = 0, uniform traction on x = L; returns (model, sol, mean tip w per case)."""
    model = build_model(box(L, B, H, *n), mat, order)
    sup = [Fixed("xmin")] + ([Symmetry("ymin"), Symmetry("ymax")] if plane_strain else [])
    sol = solve(model, sup, [SurfaceForce("xmax", f) for f in cases])
    tip = np.isclose(model.mesh.nodes[:, 0], L)
    return model, sol, sol.U.reshape(-1, 3, sol.U.shape[1])[tip, 2].mean(0)


def _timoshenko(L, B, H, mat, F=-1.0):
    I, G = B * H**3 / 12, mat.E / (2 * (1 + mat.nu))
    kappa = 10 * (1 + mat.nu) / (12 + 11 * mat.nu)
    return F * L**3 / (3 * mat.E * I) + F * L / (kappa * G * B * H)


def _summary(sol, k=None):
    """The numbers a part report takes from a solve (see rigfem/partcheck.py)."""
    c = None if k is None else np.eye(sol.U.shape[1])[k]
    p = sol.peak(c)
    return {"peak_mpa": p.value, "error_pct": p.error_pct, "at": list(p.xyz), "residual_max": sol.residuals.max(),
            "backward_max": sol.backward_errors.max(), "u_max": float(np.abs(sol.U).max())}


# ----------------------------------------------------------------------------- load range
def test_peak_and_error_estimate_over_twelve_decades():
    """Linearity of U is covered elsewhere; here the reported peak σvm ∝ load and its error
    estimate (a ratio) is load-independent, 1e-6 N … 1e6 N, and everything stays finite."""
    mags = [1e-6, 1e-3, 1.0, 1e3, 1e6]
    _, sol, w = _cantilever(100.0, 10.0, 10.0, (6, 1, 1), 2, cases=[(0, 0.3 * m, -m) for m in mags])
    ref = _summary(sol, 2)
    for k, m in enumerate(mags):
        s = _summary(sol, k)
        finite(s)
        assert s["peak_mpa"] == pytest.approx(m * ref["peak_mpa"], rel=1e-9)
        assert s["error_pct"] == pytest.approx(ref["error_pct"], rel=1e-7)
        assert s["at"] == ref["at"]
        assert w[k] == pytest.approx(m * w[2], rel=1e-9)
        assert s["backward_max"] < 1e-14


# ----------------------------------------------------------------------------- very coarse
@pytest.mark.parametrize("order", [1, 2])
def test_one_cell_mesh_is_finite_bounded_and_honest(order):
    """6 tets for a 200 mm cantilever: the displacement model is too stiff, so the mean tip
    deflection (= compliance / load for a uniform traction) lies in (0, Timoshenko]; the
    error estimate says the peak is far from converged."""
    L, B, H = 200.0, 10.0, 10.0
    model, sol, w = _cantilever(L, B, H, (1, 1, 1), order)
    assert len(model.part.tets) == 6
    exact = _timoshenko(L, B, H, STEEL)
    assert 0 < w[0] / exact <= 1.0
    s = _summary(sol)
    finite(s)
    assert np.isfinite(sol.nodal_stress).all() and s["peak_mpa"] > 0
    assert s["error_pct"] > 10
    r = sol.support_reactions["Fixed(xmin)"][0]
    assert np.allclose(r[:3], [0, 0, 1.0], atol=1e-9)  # equilibrium holds on any mesh


# ----------------------------------------------------------------------------- too fine
def test_memory_guard_names_the_parameter_and_acts_before_meshing(monkeypatch):
    import gmsh

    from rigfem.mesh import MeshSettings, mesh_part
    from rigfem.rig import load_part

    def no_meshing(*a, **k):
        raise AssertionError("gmsh meshing started before the memory guard refused")

    monkeypatch.setattr(gmsh.model.mesh, "generate", no_meshing)
    part = load_part("rail_size25", {"length": 700})
    with pytest.raises(InputError) as e:
        mesh_part(part, MeshSettings(0.2), cache=NO_CACHE)
    msg = str(e.value)
    assert msg.startswith("size_mm = 0.2 mm") and "\n" not in msg
    assert "GiB" in msg and "increase size_mm (--size)" in msg
    # the guard compares with the machine size it is given: a 4 mm rail on a 1e-4 GiB machine
    with pytest.raises(InputError, match=r"more than the machine's 0.0001 GiB"):
        mesh_part(part, MeshSettings(4.0), cache=NO_CACHE, machine_gib=1e-4)


# ----------------------------------------------------------------------------- aspect ratio 100
def test_slender_bar_aspect_100_p2_vs_euler_bernoulli():
    """1000 × 10 × 10 mm, one P2 element through the depth: tip deflection vs FL³/3EI ≤ 1 %
    (shear adds 3e-4 at L/H = 100); the backward error of the solve is reported and ~1e-16."""
    L, B, H = 1000.0, 10.0, 10.0
    _, sol, w = _cantilever(L, B, H, (100, 1, 1), 2)
    eb = -L**3 / (3 * STEEL.E * B * H**3 / 12)
    assert w[0] == pytest.approx(eb, rel=0.01)
    assert sol.backward_errors.shape == (1,) and sol.backward_errors.max() < 1e-14
    assert sol.residuals.max() < 1e-6  # ‖Ku − f‖/‖f‖ is larger for a slender part, still small
    # root bending stress at x = L/4 on the top fibre, M c / I
    x = sol.model.mesh.nodes
    top = np.isclose(x[:, 0], L / 4) & np.isclose(x[:, 2], H)
    assert sol.stress()[top, 0].mean() == pytest.approx(0.75 * L * (H / 2) / (B * H**3 / 12), rel=0.02)


def test_thin_plate_aspect_100_cylindrical_bending():
    """100 × 5 × 1 mm strip with symmetry on both long sides (plane strain, a slice of a wide
    plate): tip deflection vs FL³/(3 D b), D = E t³ / 12(1 − ν²), ≤ 1 %."""
    L, B, t = 100.0, 5.0, 1.0
    _, sol, w = _cantilever(L, B, t, (50, 1, 1), 2, plane_strain=True)
    plate = -L**3 / (3 * STEEL.E / (1 - STEEL.nu**2) * B * t**3 / 12)
    assert w[0] == pytest.approx(plate, rel=0.01)
    assert sol.backward_errors.max() < 1e-14
    finite(_summary(sol))


# ----------------------------------------------------------------------------- nu -> 0.5
NEAR_INCOMPRESSIBLE = Material("nu049", 210000.0, 0.49, 750.0, 7.85e-9)


def test_nu_049_p1_locks_p2_does_not():
    """ν = 0.49 (the largest accepted): P1 gives < 15 % of the Timoshenko tip deflection
    (volumetric locking), P2 on the same mesh is within 6 %."""
    L, B, H = 200.0, 10.0, 10.0
    exact = _timoshenko(L, B, H, NEAR_INCOMPRESSIBLE)
    with pytest.warns(UserWarning, match="volumetric locking"):  # the locking it warns of
        _, _, w1 = _cantilever(L, B, H, (20, 2, 2), 1, NEAR_INCOMPRESSIBLE)
    _, _, w2 = _cantilever(L, B, H, (20, 2, 2), 2, NEAR_INCOMPRESSIBLE)
    assert 0 < w1[0] / exact < 0.15
    assert w2[0] == pytest.approx(exact, rel=0.06)


def test_nu_above_049_is_a_clear_error():
    with pytest.raises(InputError, match=r"nu = 0\.5 is outside the allowed range \[-0\.99, 0\.49\]"):
        Material("rubber", 10.0, 0.5, 20.0, 1e-9)


def test_p1_with_nu_near_half_warns_about_locking():
    with pytest.warns(UserWarning, match="locking"):
        build_model(box(200.0, 10.0, 10.0, 4, 1, 1), NEAR_INCOMPRESSIBLE, 1)
    with warnings.catch_warnings():  # P2 and P1 with ordinary ν must stay silent
        warnings.simplefilter("error")
        build_model(box(200.0, 10.0, 10.0, 4, 1, 1), NEAR_INCOMPRESSIBLE, 2)
        build_model(box(200.0, 10.0, 10.0, 4, 1, 1), STEEL, 1)


# ----------------------------------------------------------------------------- residual check
def test_every_solve_checks_its_backward_error():
    """An unattainable tolerance must be refused, never returned as a solution."""
    model = build_model(box(100.0, 10.0, 10.0, 4, 1, 1), STEEL, 1)
    with pytest.raises(SolverError, match="backward error"):
        solve(model, [Fixed("xmin")], [SurfaceForce("xmax", (0, 0, -1.0))], solver="superlu", rtol=1e-30)


# ----------------------------------------------------------------------------- units in a scene
def test_si_material_in_a_mm_scene_is_a_clear_error():
    with pytest.raises(InputError, match=r"E = .*MPa"):
        material_from_dict({"name": "steel_si", "E": 210e9, "nu": 0.3, "sigma_u": 750e6, "density": 7850.0})


# ----------------------------------------------------------------------------- end to end
@pytest.mark.heavy  # over 10 s: the default run stays under 10 minutes
def test_check_at_100_hz_scales_the_plate_peak_by_1e4_and_stays_finite(tmp_path):
    """Original mode: plate load = 1.4 × peak pin force ∝ ω² and the FE is linear, so the
    checked peak σvm at 100 Hz (the allowed maximum) is exactly 1e4 × the 1 Hz one; the
    report JSON written for the failing case holds no NaN or infinity."""
    import json

    from rigfem.pipeline import Output, Request, run_check

    # one mesh for both (no ladder): the failing 100 Hz case would otherwise climb to a finer level
    fast = {"parts": ["plate_A"], "fidelity": "draft", "samples": 72, "frames": 0, "modes": ["original"],
            "adaptive": False}
    out = {}
    for hz in (1.0, 100.0):
        scene = tmp_path / f"hz{hz:g}.toml"
        scene.write_text('[linkage]\ntype = "four-bar"\nb2 = 480.0\nb3 = 840.0\nb4 = 780.0\nd = 1020.0\n'
                         f"speed_hz = {hz}\n")
        out[hz] = run_check(Request(scene, fast), Output(tmp_path / f"o{hz:g}"))
        finite(json.loads((tmp_path / f"o{hz:g}" / "report.json").read_text()))
    lo, hi = (out[h]["parts"][0] for h in (1.0, 100.0))
    assert hi["peak_mpa"] / lo["peak_mpa"] == pytest.approx(1e4, rel=1e-8)
    assert out[1.0]["verdict"] == "pass" and out[100.0]["verdict"] == "fail"


@pytest.mark.heavy
def test_rail_meshed_far_too_coarse_is_a_clear_error():
    """A 700 mm rail at size = 200 mm: gmsh's mesh is degenerate; refused naming size (~10 s)."""
    from rigfem.mesh import MeshSettings, mesh_part
    from rigfem.rig import load_part

    with pytest.raises(InputError, match=r"^part rail_size25: mesh quality .* change size_mm = 200 mm") as e:
        mesh_part(load_part("rail_size25", {"length": 700}), MeshSettings(200.0), cache=NO_CACHE)
    assert "\n" not in str(e.value)
