"""Validation at the edge: InputError and check_range only where user input is parsed.

A value enters rigfem once, through a boundary module (the CLI, a scene file and its schema, a
part file, a CSV, the user's function text, an output path, the environment) or the constructor
of a value type that holds its own invariants; every layer inside trusts what it is given, and a
broken invariant there is a bug (ComputeError or an assertion), never "bad input".

A library function a user's script calls directly with its own names (the FE's build_model/solve
with surface and hole names, docs/guide/own-part.md) is such an edge too: its inputs are judged by
a boundary module (rigfem.fe.inputs) that the public entry points call first, so a wrong name still
reads as bad input while the FE inside treats it as a bug.
"""

import ast
import pathlib

import rigfem

PKG = pathlib.Path(rigfem.__file__).parent

#: modules that parse user input: every function in them may raise InputError
BOUNDARY = {
    "rigfem.errors",  # defines InputError and check_range
    "rigfem.cli",  # every module of the command line
    "rigfem.schema", "rigfem.scene", "rigfem.job",  # a scene file, its [check] table, the scene stage
    "rigfem.settings",  # the [check] table's parts and presets
    "rigfem.material",  # material tables and names
    "rigfem.rig.parts",  # part files (geometry/*.toml) and their dimension overrides
    "rigfem.mesh.custom",  # a user's own part file (.geo/.step/.brep) read by gmsh
    "rigfem.io.reactions_csv", "rigfem.io.calculix",  # files read: a reactions CSV, CalculiX's output
    "rigfem.linkage.expression",  # the user's function text (synthesis)
    "rigfem.dynamics.inputs",  # a script's config dict in place of a Linkage (rigfem.dynamics.simulate)
    "rigfem.report.folder",  # output paths
    "rigfem.cache",  # the environment (RIGFEM_CACHE, RIGFEM_CACHE_MAX_GB)
    # the FE's public API takes a script's own supports, loads (surface and hole names) and solver
    # name (docs/guide/own-part.md, examples/custom_part.py): build_model/solve/load_vector judge
    # them once against the mesh here, and the FE inside trusts them
    "rigfem.fe.inputs",
    # closed forms a script calls with its own dimensions (docs/guide/own-part.md compares its FE
    # peak with plate_hole_peak_mpa): a formula's validity range is the range of its input
    "rigfem.verification.closed_form",
    # the LE10 benchmark a script solves on its own mesh, in its own length unit (unit_mm)
    "rigfem.verification.le10",
}

#: value types whose constructor (__init__/__post_init__) holds the invariants of their fields
VALUE_TYPES = {
    "rigfem.verdict.fatigue.Marin",  # the Goodman check's factors
    "rigfem.verification.convergence.StudySpec",  # a convergence study's levels, ratio, memory, order
    "rigfem.linkage.dims.Lengths", "rigfem.linkage.dims.Rails",  # a builder's or a kinematics run's lengths
    "rigfem.linkage.dims.Options", "rigfem.linkage.dims.Drive",  # its branch and masses; the crank's speed
    "rigfem.sweep.configs.SweepParams", "rigfem.sweep.run.SweepOptions",  # a sweep's inputs and options
    "rigfem.linkage.synthesis.FunctionTask",  # a function synthesis's ranges, ground, points and function
    "rigfem.linkage.synthesis.Positions",  # a motion synthesis's three positions
    "rigfem.sweep.run.Scheduler",  # a Dask scheduler's tcp://HOST:PORT
    "rigfem.context.Context",  # a job's worker processes
    "rigfem.dynamics.history.DynamicsOptions",  # a turn's samples, mass model and crank speed
}

#: What is known only once rigfem works on valid input (no four-bar on the rails, a joint off a
#: rail's holes, a peak in a toggle range, a mesh too coarse for its part, a job past the machine, a
#: synthesis whose equations have no useful solution) is an InfeasibleError, raised inside; catching
#: an InputError (a trial design that does not close) is not a refusal.  A script's own PartMesh is
#: judged whole at the edge (rigfem.fe.inputs.check_mesh: its surfaces are tet faces, its curved
#: edges tet edges), so the FE's face and edge lookups inside raise ComputeError.

NAMES = {"InputError", "check_range"}


def _module(path: pathlib.Path) -> str:
    parts = [p for p in path.relative_to(PKG.parent).with_suffix("").parts if p != "__init__"]
    return ".".join(parts)


def _in(mod: str, names: set[str]) -> bool:
    return any(mod == n or mod.startswith(n + ".") for n in names)


def sites(source: str, mod: str, names: set[str] = NAMES, boundary: bool = True) -> list[str]:
    """Every use of ``names`` (InputError/check_range) in ``source`` (imports and except clauses
    aside) outside the allowed places (``boundary``: the boundary modules), as ``module:line
    qualified.name``."""
    if boundary and _in(mod, BOUNDARY):
        return []
    found = []

    def visit(node: ast.AST, scope: list[str]) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                continue
            if isinstance(child, ast.ExceptHandler):  # catching a refusal is not making one
                for stmt in child.body:
                    visit(ast.Module([stmt], []), scope)
                continue
            inner = scope + [child.name] if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef,
                                                                ast.ClassDef)) else scope
            name = (child.id if isinstance(child, ast.Name) else
                    child.attr if isinstance(child, ast.Attribute) else None)
            if name in names:
                constructor = (len(scope) >= 2 and scope[-1] in ("__init__", "__post_init__")
                               and ".".join([mod, *scope[:-1]]) in VALUE_TYPES)
                if not constructor:
                    found.append(f"{mod}:{child.lineno} {'.'.join(scope) or '<module>'} uses {name}")
            visit(child, inner)

    visit(ast.parse(source), [])
    return found


def _key(site: str) -> str:
    """``module:function`` of a site line."""
    return f"{site.split(':')[0]}:{site.split()[1]}"


def test_input_errors_only_at_the_edge():
    """No InputError/check_range outside the boundary modules and value-type constructors:
    inside, a bad value is a bug (ComputeError or an assertion)."""
    found = [s for f in sorted(PKG.rglob("*.py")) for s in sites(f.read_text(), _module(f))]
    assert found == [], "\n".join(found)


def test_the_boundary_check_can_fail():
    """A check_range planted in the stress recovery, or an InputError in a value type's method
    other than its constructor, is caught; the same in a constructor or a boundary module is not."""
    planted = "def peak(s):\n    return check_range('s', s, 0.0)\n"
    assert sites(planted, "rigfem.fe.stress") == ["rigfem.fe.stress:2 peak uses check_range"]
    method = ("class Marin:\n    def __post_init__(self):\n        raise InputError('x')\n"
              "    def size(self):\n        raise InputError('y')\n")
    assert sites(method, "rigfem.verdict.fatigue") == ["rigfem.verdict.fatigue:5 Marin.size uses InputError"]
    assert sites(planted, "rigfem.cli.check") == []
    caught = ("def trial(x):\n    try:\n        return close(x)\n    except InputError:\n"
              "        raise InputError('y')\n")
    assert sites(caught, "rigfem.linkage.synthesis") == ["rigfem.linkage.synthesis:5 trial uses InputError"]
    assert sites("def snap():\n    raise InfeasibleError('no four-bar')\n", "rigfem.design.rig_design") == []


def test_refine_groups_are_judged_against_the_parts_groups():
    """A refine or concentrate name that is not a surface group of the part: bad input listing them."""
    import pytest

    from rigfem.errors import InputError
    from rigfem.settings import MeshSettings, check_groups

    s = MeshSettings(size_mm=10.0).refined(("bore", "rim"), ("fillet",))
    check_groups("plate", s, {"bore": 1, "rim": 2, "fillet": 3})
    with pytest.raises(InputError, match=r"refine: rim, fillet not a surface group of plate; groups: bore, top$"):
        check_groups("plate", s, {"bore": 1, "top": 2})


def test_infeasible_input_is_still_bad_input():
    """What valid input asks for but cannot be had is an InputError (exit 2), closure included."""
    from rigfem.errors import ClosureError, InfeasibleError, InputError

    assert issubclass(InfeasibleError, InputError) and issubclass(ClosureError, InfeasibleError)


#: where an InfeasibleError is raised inside (valid input that asks for what cannot be had), function
#: -> how many: a new site is listed here on purpose, never a plain out-of-range value in disguise
INFEASIBLE = {
    "rigfem.design.rig_design:snap_function": 1,  # no four-bar on the rig's rails obeys the rules
    "rigfem.design.rig_design:snap_motion": 2,  # the same; no one scale fits the rails
    "rigfem.linkage.synthesis:_dyad": 1,  # the chosen rotations make the dyad equations singular
    "rigfem.linkage.synthesis:synthesize_function": 3,  # the precision points ask for a linear map
    "rigfem.linkage.synthesis:three_position": 1,  # the rotations give a zero-length link
    "rigfem.loads.cases:_at_peak": 1,  # the peak lies in a toggle range
    "rigfem.mesh.mesher:_mesh": 2,  # the mesh's quality is below the limit; a group came out empty
    "rigfem.mesh.mesher:check_estimate": 1,  # the mesh would exceed the machine
    "rigfem.rig.layout:RailLayout.coupling": 1,  # a joint off the rail's holes
    "rigfem.sweep.bases:_reference_cases": 1,  # no configuration of the rails can run
    "rigfem.sweep.cost:check_cost": 1,  # the job would exceed the machine
}


def test_infeasible_errors_are_the_listed_ones():
    """Every InfeasibleError raised inside is one of :data:`INFEASIBLE`."""
    found: dict[str, int] = {}
    for f in sorted(PKG.rglob("*.py")):
        mod = _module(f)
        if mod == "rigfem.errors":
            continue
        for s in sites(f.read_text(), mod, names={"InfeasibleError"}, boundary=False):
            found[_key(s)] = found.get(_key(s), 0) + 1
    assert found == INFEASIBLE


def test_a_scripts_mesh_is_judged_whole_at_the_edge():
    """A PartMesh whose surface triangle is no tet face, or whose curved edge is no tet edge, is
    refused by fe_mesh with the field and what is wrong (exit 2), before the FE looks them up."""
    import numpy as np
    import pytest

    from rigfem.errors import InputError
    from rigfem.fe import fe_mesh
    from rigfem.mesh.partmesh import PartMesh

    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float)
    t = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    ok = PartMesh("two", p, t, {"base": np.array([[0, 1, 2]]), "slant": np.array([[1, 2, 4]])},
                  curved_edges=np.array([[3, 4]]), curved_points=np.array([[0.6, 0.6, 1.1]]))
    assert fe_mesh(ok, 2).nodes.shape == (5 + 9, 3)
    across = PartMesh("two", p, t, {"base": np.array([[0, 1, 2]]), "cut": np.array([[0, 1, 4]])})
    with pytest.raises(InputError, match=r"^surface 'cut': 1 of its 1 triangles are not faces of the "
                                         r"mesh's tets \(first: vertices \(0, 1, 4\)\)$"):
        fe_mesh(across, 1)
    chord = PartMesh("two", p, t, curved_edges=np.array([[0, 4]]), curved_points=np.array([[0.5, 0.5, 0.5]]))
    with pytest.raises(InputError, match=r"^curved_edges: 1 of 1 are not edges of the mesh's tets "
                                         r"\(first: vertices \(0, 4\)\)$"):
        fe_mesh(chord, 2)
    with pytest.raises(InputError, match=r"^surface 'base': vertex 5 is not a tet vertex \(0..4\)$"):
        fe_mesh(PartMesh("two", p, t, {"base": np.array([[0, 1, 5]])}), 2)
    with pytest.raises(InputError, match=r"^surface 'base' must hold whole vertex numbers, got float64 "
                                         r"values such as 0.5$"):
        fe_mesh(PartMesh("two", p, t, {"base": np.array([[0.5, 1, 2]])}), 2)
    with pytest.raises(InputError, match=r"^curved_points must be one finite point \(x, y, z\) per curved edge, "
                                         r"\(1, 3\); got float64 \(1, 2\)$"):
        fe_mesh(PartMesh("two", p, t, curved_edges=np.array([[3, 4]]), curved_points=np.array([[0.6, 0.6]])), 2)
    with pytest.raises(InputError, match=r"^surface 'nil' must be a \(K, 3\) array of tet vertices, got shape \(0,\)$"):
        fe_mesh(PartMesh("two", p, t, {"nil": []}), 1)
    # an empty (0, 3) surface of any type is empty, no curved edges may be [] (as before);
    # whole-valued floats (np.loadtxt) are vertex numbers
    loose = PartMesh("two", p, t, {"base": np.array([[0.0, 1.0, 2.0]]), "none": np.zeros((0, 3))},
                     curved_edges=[], curved_points=[])
    assert set(fe_mesh(loose, 2).surfaces) == {"base", "none"} and set(fe_mesh(loose, 1).surfaces) == {"base", "none"}
