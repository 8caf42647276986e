"""Stiffness kernel vs scikit-fem's generic assembly, and basic matrix properties."""

import numpy as np
import pytest
from fe_shapes import box
from skfem import (
    Basis,
    ElementTetP1,
    ElementTetP2,
    ElementVector,
    MeshTet,
    MeshTet2,
    asm,
)
from skfem.models.elasticity import lame_parameters, linear_elasticity

from rigfem.errors import InputError
from rigfem.fe import fe_mesh, rigid_modes, stiffness
from rigfem.fe.assembly import _chords
from rigfem.mesh import PartMesh


@pytest.mark.parametrize("order", [1, 2])
def test_stiffness_equals_skfem_generic(order):
    part = box(3, 2, 1, 3, 2, 2, jitter=0.2)
    fm = fe_mesh(part, order)
    K = stiffness(fm, 210e3, 0.3)
    el = ElementTetP1() if order == 1 else ElementTetP2()
    b = Basis(MeshTet(fm.nodes[:fm.n_vertices].T, fm.elements[:, :4].T), ElementVector(el))
    Ks = asm(linear_elasticity(*lame_parameters(210e3, 0.3)), b)
    perm = np.empty(b.N, dtype=np.int64)  # skfem DOF -> rigfem DOF 3*node + c
    n = fm.n_vertices
    for c in range(3):
        perm[b.nodal_dofs[c]] = 3 * np.arange(n) + c
        if order == 2:
            e = np.sort(b.mesh.edges, 0)
            key = e[0].astype(np.int64) * n + e[1]
            perm[b.edge_dofs[c]] = 3 * (n + np.searchsorted(np.unique(key), key)) + c
            assert np.allclose(fm.nodes[n + np.searchsorted(np.unique(key), key)], b.mesh.p[:, e].mean(1).T)
    assert abs(K[perm][:, perm] - Ks).max() <= 1e-13 * abs(Ks).max()


def test_curved_stiffness_equals_skfem_isoparametric():
    """Every mid-edge node moved off its chord: the per-quadrature-point Jacobian path against
    scikit-fem's quadratic-geometry mesh (MeshTet2) with the same 4-point rule."""
    fm = fe_mesh(box(3, 2, 1, 3, 2, 2, jitter=0.2), 2)
    n = fm.n_vertices
    fm.nodes[n:] += 0.04 * np.random.default_rng(1).uniform(-1, 1, fm.nodes[n:].shape)
    fm.curved = np.abs(_chords(fm, slice(None))).max(axis=(1, 2)) > 0
    assert fm.curved.all()
    K = stiffness(fm, 210e3, 0.3)
    m1 = MeshTet(fm.nodes[:n].T, fm.elements[:, :4].T)
    e = np.sort(m1.edges, 0)
    key = e[0].astype(np.int64) * n + e[1]
    mid = n + np.searchsorted(np.unique(key), key)
    b = Basis(MeshTet2(np.vstack([fm.nodes[:n], fm.nodes[mid]]).T, fm.elements[:, :4].T),
              ElementVector(ElementTetP2()), intorder=2)
    Ks = asm(linear_elasticity(*lame_parameters(210e3, 0.3)), b)
    perm = np.empty(b.N, dtype=np.int64)
    for c in range(3):
        perm[b.nodal_dofs[c]] = 3 * np.arange(n) + c
        perm[b.edge_dofs[c]] = 3 * mid + c
    assert abs(K[perm][:, perm] - Ks).max() <= 1e-13 * abs(Ks).max()


def test_curved_path_equals_affine_on_straight_elements():
    fm = fe_mesh(box(2, 1, 1, 4, 2, 2, jitter=0.2), 2)
    assert not fm.curved.any()
    K0 = stiffness(fm, 210e3, 0.3)
    fm.curved[:] = True
    assert abs(stiffness(fm, 210e3, 0.3) - K0).max() <= 1e-12 * abs(K0).max()


def test_distorted_curved_element_is_straightened():
    """A mid-edge node pushed past the opposite face inverts the element: it goes back to its chord."""
    part = box(1, 1, 1, 1, 1, 1)
    fm0 = fe_mesh(part, 2)
    t = fm0.elements[0]
    a, b = t[0], t[1]
    far = fm0.nodes[t[2:4]].mean(0)  # beyond the element's other edge
    mid = 0.5 * (fm0.nodes[a] + fm0.nodes[b])
    part.curved_edges = np.array([[a, b]])
    part.curved_points = (mid + 1.5 * (far - mid))[None]
    fm = fe_mesh(part, 2)
    assert fm.straightened >= 1 and not fm.curved.any()
    assert np.allclose(fm.nodes, fm0.nodes)
    part.curved_points = (mid + 0.05 * (far - mid))[None]  # mildly curved: kept
    fm = fe_mesh(part, 2)
    assert fm.straightened == 0 and fm.curved.sum() >= 1


@pytest.mark.parametrize("order", [1, 2])
def test_stiffness_symmetric_and_rigid_modes_in_kernel(order):
    fm = fe_mesh(box(2, 1, 1, 4, 2, 2, jitter=0.2), order)
    K = stiffness(fm, 210e3, 0.3)
    assert abs(K - K.T).max() <= 1e-12 * abs(K).max()
    assert abs(K @ rigid_modes(fm.nodes)).max() <= 1e-10 * abs(K).max()


def test_bad_mesh_raises():
    with pytest.raises(InputError, match="order"):
        fe_mesh(box(1, 1, 1, 1, 1, 1), 3)
    p = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0.0]])
    with pytest.raises(InputError, match="degenerate"):
        fe_mesh(PartMesh("flat", np.vstack([p, [[0, 1, 0]]]), np.array([[0, 1, 2, 3], [0, 1, 2, 4]])), 2)


@pytest.mark.heavy  # two fresh interpreters with an empty numba cache (5 s); the default run checks the
# child with numba's cache as it is (test_the_compile_child_runs_once_per_cache)
def test_first_assembly_compiles_the_kernels_in_a_child(tmp_path):
    """With numba's cache empty, one child process compiles the kernels and the assembling
    process loads each from numba's cache (compiles nothing itself); the next process starts no
    child (the marker entry)."""
    import os
    import subprocess
    import sys

    code = ("import subprocess\n"
            "children, popen = [], subprocess.Popen\n"
            "subprocess.Popen = lambda *a, **k: children.append(a) or popen(*a, **k)\n"
            "from fe_shapes import box\n"
            "from rigfem.fe import fe_mesh, stiffness\n"
            "for order in (1, 2):\n"
            "    stiffness(fe_mesh(box(3, 2, 1, 3, 2, 2, jitter=0.2), order), 210e3, 0.3)\n"
            "import rigfem.fe.kernels as k\n"
            "fs = (k.block_pattern, k.add_elastic_blocks)\n"
            "print(sum(sum(f.stats.cache_misses.values()) for f in fs),\n"
            "      sum(sum(f.stats.cache_hits.values()) for f in fs), len(children))\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "RIGFEM_CACHE": str(tmp_path / "cache"),
           "PYTHONPATH": os.pathsep.join([os.path.dirname(__file__), os.environ.get("PYTHONPATH", "")])}
    got = []
    for _ in range(2):
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=900)
        assert r.returncode == 0, r.stderr
        got.append(tuple(map(int, r.stdout.split())))
    (misses, hits, children), again = got
    assert misses == 0 and hits >= 2 and children == 1  # compiled by the child, loaded here
    assert again[0] == 0 and again[2] == 0  # the marker: no second child


def test_once_the_kernels_are_loaded_no_compile_child_is_started(tmp_path, monkeypatch):
    """A later cache without the marker (a changed RIGFEM_CACHE) starts no child that nobody
    would wait for: the kernels are loaded in this process already."""
    import subprocess

    from rigfem.fe import assembly

    assembly._kernels()
    started = []
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: started.append(a))
    from rigfem.cache import Cache

    empty = Cache(tmp_path / "empty", 10**9)
    assembly.start_compiling(empty)
    assembly.compiled(empty)
    assert started == []


def test_the_warm_up_assembles_one_p1_and_one_p2_tetrahedron(monkeypatch):
    """The compile child (:func:`compile_kernels`) assembles a real unit tetrahedron at both orders,
    so numba compiles every signature a part's assembly uses, and marks itself the child, so that it
    starts no compile child of its own."""
    from rigfem.fe import assembly
    from rigfem.fe.assembly import volume

    seen, real = [], assembly.stiffness
    monkeypatch.setattr(assembly, "_COMPILING", False)
    monkeypatch.setattr(assembly, "_compiler", False)  # this process starts no compile child
    monkeypatch.setattr(assembly, "stiffness",
                        lambda fm, E, nu: seen.append((fm.order, len(fm.nodes), volume(fm))) or real(fm, E, nu))
    assembly.compile_kernels()
    assert assembly._COMPILING is True
    assert [(order, n) for order, n, _ in seen] == [(1, 4), (2, 10)]
    assert [v for *_, v in seen] == pytest.approx([1 / 6, 1 / 6], rel=1e-12)


def test_a_compile_child_starts_no_child_of_its_own(tmp_path, monkeypatch):
    """The compile child is marked twice, by :data:`_COMPILING` in its code and by its environment,
    so that no single slip starts a chain of children (each waiting for the next, until the
    memory is full)."""
    import subprocess

    from rigfem.cache import Cache
    from rigfem.fe import assembly

    started = []
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: started.append(k.get("env", {})) or object())
    monkeypatch.setattr(assembly, "_COMPILING", False)
    empty = Cache(tmp_path / "empty", 10**9)
    for child in (True, False):
        monkeypatch.setattr(assembly, "_compiler", None)
        if child:
            monkeypatch.setenv(assembly._CHILD_ENV, "1")
        else:
            monkeypatch.delenv(assembly._CHILD_ENV)
        assembly.start_compiling(empty)
        assert len(started) == (0 if child else 1)
    assert started[0].get(assembly._CHILD_ENV)  # and the child it starts carries the mark


def _no_compiler_yet(monkeypatch):
    """rigfem.fe.assembly as in a process that has started no compile child and is none."""
    from rigfem.fe import assembly

    monkeypatch.setattr(assembly, "_COMPILING", False)
    monkeypatch.setattr(assembly, "_compiler", None)
    monkeypatch.delenv(assembly._CHILD_ENV, raising=False)
    return assembly


def test_the_compile_child_runs_once_per_cache(tmp_path, monkeypatch):
    """Waiting for the kernels with no child started starts one with the cache given; it runs the
    kernels' compile to the end (exit 0) and, waited for, marks that cache, so that the next
    process with the same cache starts none."""
    import subprocess

    from rigfem.cache import Cache

    assembly = _no_compiler_yet(monkeypatch)
    started, popen = [], subprocess.Popen
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: started.append(popen(*a, **k)) or started[-1])
    cache = Cache(tmp_path / "cache", 10**9)
    assembly.compiled(cache)
    assert len(started) == 1 and started[0].returncode == 0
    assert cache.has("kernels", assembly._marker())
    monkeypatch.setattr(assembly, "_compiler", None)  # the next process
    assembly.start_compiling(cache)
    assert len(started) == 1


def test_a_compile_child_that_cannot_start_or_hangs_leaves_the_compile_here(tmp_path, monkeypatch):
    """No child can start (it is tried once), or it hangs (it is killed): nothing is raised and
    nothing marked, this process compiles; an interrupt while waiting is not swallowed."""
    import subprocess

    from rigfem.cache import Cache

    assembly = _no_compiler_yet(monkeypatch)
    cache, tries = Cache(tmp_path / "cache", 10**9), []

    def refuse(*a, **k):
        tries.append(a)
        raise OSError("no more processes")

    monkeypatch.setattr(subprocess, "Popen", refuse)
    assembly.start_compiling(cache)  # started early, as the check does
    assembly.compiled(cache)
    assert len(tries) == 1 and not cache.has("kernels", assembly._marker())

    class Hung:
        killed = False

        def wait(self, timeout=None):
            if timeout is not None:
                raise subprocess.TimeoutExpired("compile", timeout)

        def kill(self):
            type(self).killed = True

    class Interrupted(Hung):
        def wait(self, timeout=None):
            if timeout is not None:
                raise KeyboardInterrupt

    monkeypatch.setattr(assembly, "_compiler", (Hung(), cache))
    assembly.compiled(cache)
    assert Hung.killed and not cache.has("kernels", assembly._marker())
    monkeypatch.setattr(assembly, "_compiler", (Interrupted(), cache))
    with pytest.raises(KeyboardInterrupt):
        assembly.compiled(cache)


def test_volume_over_more_elements_than_one_chunk():
    """The volume sums its chunks of 65536 elements: a jittered box of 82944 tetrahedra."""
    from rigfem.fe.assembly import volume

    fm = fe_mesh(box(2.0, 3.0, 5.0, 24, 24, 24, jitter=0.2), 1)
    assert len(fm.elements) > 65536
    assert volume(fm) == pytest.approx(30.0, rel=1e-12)


def test_straightened_elements_come_back_from_the_cache_checked(tmp_path, monkeypatch):
    """A warm mesh takes the straightened elements from the cache entry of its own P2 mesh (the
    Jacobian test is not run again; the same nodes as computed); another mesh does not take them;
    an entry with element numbers out of range is recomputed, not used."""
    from rigfem.cache import Cache
    from rigfem.fe import assembly

    cache = Cache(tmp_path / "cache", 10**9)
    part = box(1, 1, 1, 1, 1, 1)
    fm0 = fe_mesh(box(1, 1, 1, 1, 1, 1), 2)
    t = fm0.elements[0]
    a, b = t[0], t[1]
    far, mid = fm0.nodes[t[2:4]].mean(0), 0.5 * (fm0.nodes[a] + fm0.nodes[b])
    runs, real = [], assembly._straighten_distorted
    monkeypatch.setattr(assembly, "_straighten_distorted", lambda fm: runs.append(1) or real(fm))
    part.curved_edges = np.array([[a, b]])
    part.curved_points = (mid + 1.5 * (far - mid))[None]  # inverted: straightened
    cold = fe_mesh(part, 2, cache)
    warm = fe_mesh(part, 2, cache)
    assert len(runs) == 1
    assert warm.straightened == cold.straightened >= 1
    assert np.array_equal(warm.nodes, cold.nodes) and np.array_equal(warm.curved, cold.curved)
    part.curved_points = (mid + 0.05 * (far - mid))[None]  # mildly curved: another mesh, kept curved
    mild = fe_mesh(part, 2, cache)
    assert len(runs) == 2 and mild.straightened == 0 and mild.curved.sum() >= 1
    part.curved_points = (mid + 1.5 * (far - mid))[None]
    fe_mesh(part, 2, cache.without("straightened"))  # the kind switched off (benchmarks/bench_cache.py)
    assert len(runs) == 3

    poisoned = Cache(tmp_path / "poisoned", 10**9)
    monkeypatch.setattr(assembly, "_straighten_distorted", lambda fm: np.array([10**6]))
    fe_mesh(part, 2, poisoned)  # stored as computed: element 10**6 of 6
    monkeypatch.setattr(assembly, "_straighten_distorted", lambda fm: runs.append(1) or real(fm))
    again = fe_mesh(part, 2, poisoned)
    assert len(runs) == 4 and again.straightened == cold.straightened and np.array_equal(again.nodes, cold.nodes)


def test_stiffness_in_chunks_equals_one_chunk():
    """The stiffness sums its elements in chunks: any chunk size gives the same matrix."""
    fm = fe_mesh(box(2, 1, 1, 3, 2, 2, jitter=0.2), 1)
    K = stiffness(fm, 210e3, 0.3)
    for chunk in (7, len(fm.elements) - 1):
        assert abs(stiffness(fm, 210e3, 0.3, chunk=chunk) - K).max() <= 1e-12 * abs(K).max()


def test_a_mesh_of_the_same_nodes_in_another_element_order_is_straightened_on_its_own(tmp_path):
    """The straightened elements' cache entry is keyed by the nodes and the elements: the same
    nodes with the elements in another order do not take the first mesh's element numbers."""
    from rigfem.cache import Cache

    cache = Cache(tmp_path / "cache", 10**9)
    part = box(1, 1, 1, 1, 1, 1)
    fm0 = fe_mesh(box(1, 1, 1, 1, 1, 1), 2)
    t = fm0.elements[0]
    far, mid = fm0.nodes[t[2:4]].mean(0), 0.5 * (fm0.nodes[t[0]] + fm0.nodes[t[1]])
    part.curved_edges = np.array([[t[0], t[1]]])
    part.curved_points = (mid + 1.5 * (far - mid))[None]
    turned = PartMesh(part.name, part.points, part.tets[::-1].copy(), surfaces=part.surfaces)
    turned.curved_edges, turned.curved_points = part.curved_edges, part.curved_points
    first, alone = fe_mesh(part, 2, cache), fe_mesh(turned, 2)
    assert np.array_equal(fe_mesh(turned, 2, cache).nodes, alone.nodes)
    assert np.array_equal(first.nodes, alone.nodes)  # the same nodes: only the elements' order differs


def test_a_parts_own_surfaces_of_any_integer_type_give_the_same_p2_surfaces():
    """A script's PartMesh may hold its surfaces' triangles as gmsh's unsigned tags: fe_mesh reads
    them as int64 (uint64 mixed with int64 would turn into floats in numpy)."""
    part = box(2, 1, 1, 2, 1, 1)
    own = PartMesh(part.name, part.points, part.tets,
                   surfaces={k: np.asarray(v, dtype=np.uint64) for k, v in part.surfaces.items()})
    want, got = fe_mesh(part, 2).surfaces, fe_mesh(own, 2).surfaces
    assert set(got) == set(want)
    assert all(got[k].dtype == np.int64 and np.array_equal(got[k], want[k]) for k in want)
