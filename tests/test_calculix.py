"""CalculiX deck writer, runner and .frd reader against closed form and an independent skfem solve."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from skfem import (
    Basis,
    ElementTetP2,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshTet,
    asm,
    condense,
    solve,
)
from skfem.models.elasticity import lame_parameters, linear_elasticity

from rigfem.cache import NO_CACHE
from rigfem.errors import InputError
from rigfem.tensors import von_mises
from rigfem.io import CalculixError, read_frd, run_ccx, write_inp

E, NU = 210_000.0, 0.3  # MPa


def _p2_model(mesh: MeshTet):
    """Scalar P2 basis (node numbering) and vector basis; vector dof of node k, comp c = 3k + c."""
    scalar = Basis(mesh, ElementTetP2())
    vector = Basis(mesh, ElementVector(ElementTetP2()))
    assert np.array_equal(vector.nodal_dofs[0] // 3, scalar.nodal_dofs[0])  # interleaved layout
    return scalar, vector


def _skfem_solve(vector: Basis, fixed_dofs: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Plain scikit-fem linear elasticity + scipy direct solve; returns (N, 3) displacement."""
    K = asm(linear_elasticity(*lame_parameters(E, NU)), vector)
    return solve(*condense(K, f, D=fixed_dofs)).reshape(-1, 3)


def _nodal_stress(scalar: Basis, u: np.ndarray) -> np.ndarray:
    """Element stress evaluated at each element's 10 nodes, averaged over the elements (ccx's recovery)."""
    mesh, el = scalar.mesh, scalar.elem
    lam, mu = lame_parameters(E, NU)
    X = el.doflocs.T  # (3, 10) reference node locations
    dphi = np.array([el.lbasis(X, i)[1] for i in range(10)])  # (10 basis, 3 ref dirs, 10 points)
    invJ = mesh.mapping().invDF(X)  # (3, 3, nelems, 10)
    ue = u[scalar.element_dofs]  # (10, nelems, 3)
    # grad u[c, j] at (elem, point) = sum_b ue[b, e, c] * dphi[b, k, p] * invJ[k, j, e, p]
    G = np.einsum("bec,bkp,kjep->epcj", ue, dphi, invJ)
    eps = 0.5 * (G + G.transpose(0, 1, 3, 2))
    tr = np.trace(eps, axis1=2, axis2=3)
    sig = 2 * mu * eps + lam * tr[..., None, None] * np.eye(3)
    i, j = [0, 1, 2, 0, 1, 2], [0, 1, 2, 1, 2, 0]
    voigt = sig[..., i, j]
    acc = np.zeros((scalar.N, 6))
    cnt = np.zeros(scalar.N)
    dofs = scalar.element_dofs.T  # (nelems, 10)
    np.add.at(acc, dofs, voigt)
    np.add.at(cnt, dofs, 1.0)
    return acc / cnt[:, None]


def _cantilever(L=200.0, h=10.0, nx=30, ny=2):
    mesh = MeshTet.init_tensor(np.linspace(0, L, nx + 1), np.linspace(0, h, ny + 1), np.linspace(0, h, ny + 1))
    return mesh.with_boundaries({"root": lambda x: x[0] < 1e-9, "tip": lambda x: x[0] > L - 1e-9})


@pytest.mark.tool("ccx")
def test_cantilever_against_euler_bernoulli_and_skfem(tmp_path):
    L, h, P = 200.0, 10.0, 100.0  # mm, mm, N (tip shear in -z)
    mesh = _cantilever(L, h)
    scalar, vector = _p2_model(mesh)
    # consistent nodal loads of a uniform traction on the tip face, total P
    tip = FacetBasis(mesh, ElementVector(ElementTetP2()), facets=mesh.boundaries["tip"])
    f = asm(LinearForm(lambda v, w: -P / h**2 * v[2]), tip)
    assert np.isclose(f.sum(), -P)
    fixed_nodes = scalar.get_dofs("root").all()
    fixed_dofs = (3 * fixed_nodes[:, None] + np.arange(3)).ravel()

    u_sk = _skfem_solve(vector, fixed_dofs, f)
    s_sk = _nodal_stress(scalar, u_sk)

    nodes = scalar.doflocs.T
    mask = np.zeros((scalar.N, 3), bool)
    mask[fixed_nodes] = True
    deck = write_inp(tmp_path / "cantilever.inp", nodes, scalar.element_dofs.T, (E, NU, 7.85e-9), mask,
                     f.reshape(-1, 3))
    res = run_ccx(deck, threads=1)
    u_cx, s_cx = res.displacement[0], res.stress[0]

    tip_nodes = scalar.get_dofs("tip").all()
    w_cx, w_sk = u_cx[tip_nodes, 2].mean(), u_sk[tip_nodes, 2].mean()
    # Timoshenko: bending P L^3 / 3EI plus shear P L / (kappa G A), kappa = 10(1+nu)/(12+11nu)
    inertia, area, G = h**4 / 12, h**2, E / (2 * (1 + NU))
    w_eb = -P * L**3 / (3 * E * inertia)
    w_timo = w_eb - P * L / (10 * (1 + NU) / (12 + 11 * NU) * G * area)
    assert w_cx == pytest.approx(w_eb, rel=0.03)  # Euler-Bernoulli, a few %
    assert w_cx == pytest.approx(w_timo, rel=0.01)  # with shear, 1 %
    # same model solved twice: frd holds 5 significant digits, so agreement is ~1e-5
    assert w_cx == pytest.approx(w_sk, rel=5e-3)
    assert np.abs(u_cx - u_sk).max() <= 1e-4 * np.abs(u_sk).max()
    vm_cx, vm_sk = von_mises(s_cx), von_mises(s_sk)
    assert vm_cx.max() == pytest.approx(vm_sk.max(), rel=1e-2)
    assert np.abs(vm_cx - vm_sk).max() <= 1e-4 * vm_sk.max()
    # root bending stress at mid-span (away from the clamp): M c / I
    mid = np.isclose(nodes[:, 0], L / 2) & np.isclose(nodes[:, 2], h)
    assert s_cx[mid, 0].mean() == pytest.approx(P * (L / 2) * (h / 2) / inertia, rel=0.01)


@pytest.mark.tool("ccx")
def test_node_order_on_distorted_mesh(tmp_path):
    """Randomly distorted P2 tets, random loads: ccx and skfem agree node by node."""
    rng = np.random.default_rng(4)
    mesh = MeshTet.init_tensor(*(np.linspace(0, 1, 4),) * 3)
    p = mesh.p.copy()
    interior = np.all((p > 1e-9) & (p < 1 - 1e-9), axis=0)
    p[:, interior] += rng.uniform(-0.15, 0.15, (3, interior.sum()))
    p = p * np.array([[20.0], [8.0], [5.0]])
    mesh = MeshTet(p, mesh.t)
    scalar, vector = _p2_model(mesh)
    nodes = scalar.doflocs.T
    fixed_nodes = np.flatnonzero(nodes[:, 0] < 1e-9)
    fixed_dofs = (3 * fixed_nodes[:, None] + np.arange(3)).ravel()
    f = np.zeros((scalar.N, 3))
    loaded = np.flatnonzero(nodes[:, 0] > 20 - 1e-9)
    f[loaded] = rng.normal(0.0, 10.0, (len(loaded), 3))
    u_sk = _skfem_solve(vector, fixed_dofs, f.ravel())
    s_sk = _nodal_stress(scalar, u_sk)
    # flip half of the elements: the writer must renumber them, not reject or mis-order
    elements = scalar.element_dofs.T.copy()
    elements[::2] = elements[::2][:, [0, 2, 1, 3, 6, 5, 4, 7, 9, 8]]
    pairs = np.column_stack([np.repeat(fixed_nodes, 3), np.tile(np.arange(3), len(fixed_nodes))])
    res = run_ccx(write_inp(tmp_path / "d.inp", nodes, elements, (E, NU), pairs, [f, -2 * f]))
    assert res.displacement.shape == (2, scalar.N, 3)
    assert np.abs(res.displacement[0] - u_sk).max() <= 1e-4 * np.abs(u_sk).max()
    assert np.abs(res.displacement[1] + 2 * u_sk).max() <= 2e-4 * np.abs(u_sk).max()
    vm = von_mises(s_sk)
    assert np.abs(von_mises(res.stress[0]) - vm).max() <= 1e-4 * vm.max()


def test_p2_edge_order_is_c3d10():
    """skfem's P2 midside nodes sit on C3D10's edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4, in that order."""
    rng = np.random.default_rng(0)
    mesh = MeshTet(rng.uniform(size=(3, 4)) + np.eye(3, 4), np.array([[0], [1], [2], [3]]))
    x = Basis(mesh, ElementTetP2()).doflocs[:, Basis(mesh, ElementTetP2()).element_dofs[:, 0]].T
    for k, (a, b) in enumerate([(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]):
        assert np.allclose(x[4 + k], 0.5 * (x[a] + x[b]))


def test_von_mises_closed_form():
    assert von_mises(np.array([100.0, 0, 0, 0, 0, 0])) == pytest.approx(100.0)
    assert von_mises(np.array([0.0, 0, 0, 50.0, 0, 0])) == pytest.approx(50.0 * np.sqrt(3))
    assert von_mises(np.array([[7.0, 7, 7, 0, 0, 0]]))[0] == pytest.approx(0.0)


def test_bad_input(tmp_path):
    nodes = np.eye(4, 3)
    tet = np.array([[0, 1, 2, 3]])
    f = np.zeros((4, 3))
    with pytest.raises(InputError, match="material.nu"):
        write_inp(tmp_path / "x.inp", nodes, tet, (E, 0.5), np.zeros((0, 2), int), f)
    with pytest.raises(InputError, match="elements"):
        write_inp(tmp_path / "x.inp", nodes, np.array([[0, 1, 2, 4]]), (E, NU), np.zeros((0, 2), int), f)
    with pytest.raises(InputError, match="fixed"):
        write_inp(tmp_path / "x.inp", nodes, tet, (E, NU), np.array([[0, 3]]), f)
    with pytest.raises(InputError, match="nodal_forces"):
        write_inp(tmp_path / "x.inp", nodes, tet, (E, NU), np.array([[0, 0]]), np.zeros((3, 3)))


@pytest.mark.tool("ccx")
def test_ccx_failure_reports_tail(tmp_path):
    """A deck ccx rejects raises CalculixError carrying ccx's own message."""
    deck = tmp_path / "bad.inp"
    deck.write_text("*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n*ELEMENT,TYPE=C3D4,ELSET=E\n1,1,2,3,4\n"
                    "*STEP\n*STATIC\n*END STEP\n")
    with pytest.raises(CalculixError, match="no material was assigned"):
        run_ccx(deck)


def test_read_frd_fixed_width(tmp_path):
    """Values written edge to edge (negative signs) are split by column, not by whitespace."""
    frd = tmp_path / "r.frd"
    frd.write_text(
        "    1C\n    2C                             2                                     1\n"
        " -1         1 0.00000E+00 0.00000E+00 0.00000E+00\n -1         2 1.00000E+00 0.00000E+00 0.00000E+00\n"
        " -3\n -4  DISP        4    1\n -5  D1          1    2    1    0\n"
        " -1         1 0.00000E+00 0.00000E+00 0.00000E+00\n -1         2-9.17108E-01-1.00000E-03-4.28571E-05\n"
        " -3\n 9999\n")
    r = read_frd(frd)
    assert np.allclose(r.displacement[0, 1], [-0.917108, -1e-3, -4.28571e-5])
    assert r.stress.shape == (0, 2, 6)


@pytest.mark.tool("ccx")
def test_equations_match_elimination(tmp_path):
    """*EQUATION constraints (tip tied in z, inclined n·u = 0 on the top edge) vs skfem with u = T u_r."""
    mesh = MeshTet.init_tensor(np.linspace(0, 40, 9), np.linspace(0, 6, 3), np.linspace(0, 6, 3))
    scalar, vector = _p2_model(mesh)
    nodes = scalar.doflocs.T
    root = np.flatnonzero(nodes[:, 0] < 1e-9)
    tip = np.flatnonzero(nodes[:, 0] > 40 - 1e-9)
    edge = np.flatnonzero((nodes[:, 2] > 6 - 1e-9) & (nodes[:, 1] < 1e-9) & (nodes[:, 0] > 1e-9) & (nodes[:, 0] < 40))
    f = np.zeros((scalar.N, 3))
    f[tip] = [5.0, 3.0, -20.0]
    n = np.array([1.0, 2.0, 2.0]) / 3.0
    eqs = [(np.array([k, tip[0]]), np.array([2, 2]), np.array([1.0, -1.0])) for k in tip[1:]]
    eqs += [(np.array([k, k, k]), np.array([2, 0, 1]), n[[2, 0, 1]]) for k in edge]
    # independent solve: eliminate each dependent dof, u_dep = -sum(c_i u_i) / c_dep
    ndof = 3 * scalar.N
    T = np.eye(ndof)
    for nd, dd, cc in eqs:
        dep = 3 * nd[0] + dd[0]
        T[dep] = 0.0
        T[dep, 3 * nd[1:] + dd[1:]] = -cc[1:] / cc[0]
    keep = np.setdiff1d(np.arange(ndof), [3 * nd[0] + dd[0] for nd, dd, _ in eqs])
    fixed = np.searchsorted(keep, (3 * root[:, None] + np.arange(3)).ravel())
    K = asm(linear_elasticity(*lame_parameters(E, NU)), vector).toarray()
    T = T[:, keep]
    u_sk = (T @ solve(*condense(csr_matrix(T.T @ K @ T), T.T @ f.ravel(), D=fixed))).reshape(-1, 3)
    assert np.allclose(u_sk[tip, 2], u_sk[tip[0], 2]) and np.allclose(u_sk[edge] @ n, 0.0, atol=1e-12)
    mask = np.zeros((scalar.N, 3), bool)
    mask[root] = True
    res = run_ccx(write_inp(tmp_path / "eq.inp", nodes, scalar.element_dofs.T, (E, NU), mask, f, equations=eqs))
    assert np.abs(res.displacement[0] - u_sk).max() <= 1e-4 * np.abs(u_sk).max()


@pytest.mark.heavy  # over 10 s: the default run stays under 10 minutes
@pytest.mark.tool("ccx")
def test_rail_rigfem_vs_calculix(tmp_path):
    """700 mm crank rail on two pins (ShaftInHole springs), screw bearing loads at the far end, 2 cases."""
    from rigfem.fe import BearingLoad, ShaftInHole, build_model
    from rigfem.fe import solve as fe_solve
    from rigfem.io import export_model
    from rigfem.material import get_material
    from rigfem.mesh import MeshSettings, mesh_part
    from rigfem.rig import load_part

    holes = ("hole_00", "hole_01", "hole_10", "hole_11")
    pm = mesh_part(load_part("rail_size25", {"length": 700}), MeshSettings(size_mm=16.0, refine=holes, local_size_mm=5.0),
                   cache=NO_CACHE)
    model = build_model(pm, get_material("rig_steel"), order=2)
    # pins in the pivot holes; on hole_00 only the side the pin bears on (springs on half the wall)
    supports = [ShaftInHole("hole_00", direction=(-1.0, 0.0, 0.0)), ShaftInHole("hole_01")]
    cases = [[BearingLoad("hole_10", (300.0, 200.0, 0.0)), BearingLoad("hole_11", (300.0, 200.0, 0.0))],
             [BearingLoad("hole_10", (-250.0, 0.0, 0.0)), BearingLoad("hole_11", (0.0, -250.0, 0.0))]]
    sol = fe_solve(model, supports, cases)
    res = run_ccx(export_model(model, supports, cases, tmp_path / "rail.inp"), threads=1)
    n = len(model.mesh.nodes)
    tip = int(np.argmax(model.mesh.nodes[:, 0]))
    for k in range(2):
        c = np.eye(2)[k]
        u_fe, u_cx = sol.displacement(c), res.displacement[k, :n]
        vm_fe, vm_cx = sol.von_mises(c), von_mises(res.stress[k, :n])
        # the tolerances: tip displacement 0.5 %, peak von Mises 1 %
        assert np.linalg.norm(u_cx[tip] - u_fe[tip]) <= 5e-3 * np.linalg.norm(u_fe[tip])
        assert vm_cx.max() == pytest.approx(vm_fe.max(), rel=1e-2)
        # the same model: every node agrees to the .frd's 5 significant digits
        assert np.abs(u_cx - u_fe).max() <= 1e-4 * np.abs(u_fe).max()
        assert np.abs(vm_cx - vm_fe).max() <= 1e-4 * vm_fe.max()


@pytest.mark.tool("ccx")
def test_cross_check_free_body(tmp_path):
    """Self-equilibrated loads on a free box: ccx's 3-2-1 rigid motion is removed before comparing."""
    from fe_shapes import box

    from rigfem.fe import FreeBody, SurfaceForce, build_model
    from rigfem.material import get_material
    from rigfem.verification import cross_check

    model = build_model(box(60.0, 10.0, 8.0, 12, 2, 2), get_material("rig_steel"), order=2)
    cases = [[SurfaceForce("xmin", (-500.0, 0.0, 0.0)), SurfaceForce("xmax", (500.0, 0.0, 0.0))],
             [SurfaceForce("xmin", (0.0, 0.0, 100.0)), SurfaceForce("xmax", (0.0, 0.0, 100.0)),
              SurfaceForce("zmin", (0.0, 0.0, -200.0))]]
    result = cross_check(model, [FreeBody()], cases, workdir=tmp_path)
    for c in result:
        assert abs(c.peak_rel_diff) < 1e-4 and c.displacement_rel_diff < 1e-4
    assert (tmp_path / "model.inp").is_file() and (tmp_path / "job.frd").is_file()
    assert result[0].peak_von_mises == pytest.approx(500.0 / 80.0, rel=1e-9)  # uniform tension, exact in P2
    # a load combination of an existing solution (how `rigfem check` superposes unit cases)
    from rigfem.fe import solve as fe_solve

    sol = fe_solve(model, [FreeBody()], cases)
    (combo,) = cross_check(model, [FreeBody()], solution=sol, coef=np.array([[1.0, -0.5]]))
    assert combo.peak_von_mises == pytest.approx(sol.von_mises(np.array([1.0, -0.5])).max())
    assert abs(combo.peak_rel_diff) < 1e-4 and combo.displacement_rel_diff < 1e-4


@pytest.mark.tool("ccx")
@pytest.mark.heavy
def test_reference_scene_against_calculix():
    """Every part case of `rigfem verify --against calculix final-cm` (draft): README claims all 12
    within 0.0012 % (results/benchmarks/calculix_verify_final-cm.md); peak 0.002 %, displacement 0.001 %."""
    from rigfem.verification import verify_job
    from stages import job_of

    rows = verify_job(job_of("final-cm", {"fidelity": "draft", "frames": 0}))
    assert len(rows) == 12
    for r in rows:
        assert abs(r["peak_rel_diff"]) < 2e-5 and r["displacement_rel_diff"] < 1e-5, r


@pytest.mark.tool("ccx")
def test_gravity_against_ccx_body_load(tmp_path):
    """rigfem's consistent gravity loads (P1 and P2) against ccx's own *DLOAD GRAV on the same mesh."""
    from fe_shapes import box

    from rigfem.fe import Fixed, Gravity, build_model, constraints
    from rigfem.fe import solve as fe_solve
    from rigfem.material import get_material

    for order in (1, 2):
        model = build_model(box(80.0, 8.0, 12.0, 10, 2, 2, jitter=0.2), get_material("rig_steel"), order=order)
        g = (0.0, 3000.0, -9810.0)  # mm/s²
        sol = fe_solve(model, [Fixed("xmin")], [[Gravity(g)]])
        fixed, _, _ = constraints(model.mesh, {}, [Fixed("xmin")], model.material.E)
        deck = write_inp(tmp_path / f"grav{order}.inp", model.mesh.nodes, model.mesh.elements, model.material,
                         np.column_stack([fixed // 3, fixed % 3]), np.zeros((len(model.mesh.nodes), 3)), gravity=g)
        res = run_ccx(deck)
        u = sol.displacement()
        assert np.abs(res.displacement[0] - u).max() <= 1e-4 * np.abs(u).max()
        vm = sol.von_mises()
        assert von_mises(res.stress[0]).max() == pytest.approx(vm.max(), rel=1e-4)


@pytest.mark.tool("ccx")
def test_hole_pressure_against_ccx_face_load(tmp_path):
    """rigfem's Pressure on a curved hole wall (P2) against ccx's own *DLOAD face pressure."""
    from fe_shapes import plate_with_hole

    from rigfem.fe import Pressure, Symmetry, build_model, constraints
    from rigfem.fe import solve as fe_solve
    from rigfem.material import get_material

    model = build_model(plate_with_hole(60.0, 40.0, 5.0, 6.0, 5.0, 1.5), get_material("rig_steel"), order=2)
    supports = [Symmetry("xsym"), Symmetry("ysym"), Symmetry("zsym")]
    sol = fe_solve(model, supports, [[Pressure("hole", 50.0)]])
    fixed, _, _ = constraints(model.mesh, model.part.holes, supports, model.material.E)
    deck = write_inp(tmp_path / "p.inp", model.mesh.nodes, model.mesh.elements, model.material,
                     np.column_stack([fixed // 3, fixed % 3]), np.zeros((len(model.mesh.nodes), 3)),
                     pressure=(model.mesh.surfaces["hole"], 50.0))
    res = run_ccx(deck)
    u, vm = sol.displacement(), sol.von_mises()
    assert np.abs(res.displacement[0] - u).max() <= 1e-4 * np.abs(u).max()
    assert np.abs(von_mises(res.stress[0]) - vm).max() <= 1e-4 * vm.max()
