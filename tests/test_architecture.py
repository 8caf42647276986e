"""The package's structure: layers import one way only, no import cycles, a curated public API.

Layers follow the data path (configuration -> linkage geometry and motion -> reactions -> part
load cases -> mesh -> solution -> verdict -> report); a module may import its own layer and the layers below, never above.
"""

import ast
import importlib
import os
import pathlib
import subprocess
import sys

import pytest

import rigfem

PKG = pathlib.Path(rigfem.__file__).parent
#: lowest first; every rigfem module belongs to exactly one layer
LAYERS = [
    ("rigfem.errors", "rigfem.files", "rigfem.memory", "rigfem.material", "rigfem.geometry",
     "rigfem.observer", "rigfem.tensors"),  # geometry: part files (data)
    ("rigfem.cache",),
    ("rigfem.context",),
    ("rigfem.rig",),
    ("rigfem.settings",),
    ("rigfem.schema", "rigfem.scene"),
    ("rigfem.linkage",),
    ("rigfem.dynamics",),
    ("rigfem.loads",),
    ("rigfem.verdict",),
    ("rigfem.mesh",),
    ("rigfem.fe",),
    ("rigfem.io",),
    ("rigfem.job",),
    ("rigfem.report",),
    ("rigfem.pipeline",),
    ("rigfem.check",),  # the deprecated alias of rigfem.pipeline's run_check
    ("rigfem.verification", "rigfem.sweep"),
    ("rigfem.design",),
    ("rigfem.cli", "rigfem.__main__", "rigfem.studies"),  # studies: the deprecated aliases of the three above
]
SUBPACKAGES = ("rig", "linkage", "dynamics", "loads", "mesh", "fe", "verdict", "report", "io", "sweep", "verification", "design")


def _modules() -> dict[str, pathlib.Path]:
    mods = {}
    for f in PKG.rglob("*.py"):
        rel = f.relative_to(PKG).with_suffix("")
        parts = [p for p in rel.parts if p != "__init__"]
        mods[".".join(["rigfem", *parts])] = f
    return mods


def _imports(path: pathlib.Path, name: str) -> set[str]:
    """Every rigfem module ``path`` imports, at any depth (function-level imports count too)."""
    out = set()
    pkg = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("rigfem")}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(pkg.split(".")[: len(pkg.split(".")) - node.level + 1] + ([base] if base else []))
            if base.startswith("rigfem"):
                out.add(base)
                out |= {f"{base}.{a.name}" for a in node.names}
    return out


def _layer(mod: str) -> int:
    for i, layer in enumerate(LAYERS):
        if any(mod == p or mod.startswith(p + ".") for p in layer):
            return i
    return -1


MODS = _modules()
GRAPH = {m: {i for i in _imports(f, m) if i in MODS and i != m} for m, f in MODS.items()}


def test_every_module_has_a_layer():
    assert [m for m in MODS if m != "rigfem" and _layer(m) < 0] == []


def _upward(graph: dict[str, set[str]]) -> list[str]:
    return sorted(f"{m} imports {i}" for m, deps in graph.items() if m != "rigfem"
                  for i in deps if _layer(i) > _layer(m))


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in list(graph):
        if v not in index:
            visit(v)
    return found


def test_layers_import_one_way():
    assert _upward(GRAPH) == []


def test_no_import_cycles():
    # a module importing its own (lazy) package __init__ is not an edge back
    graph = {m: {i for i in deps if not (MODS[i].name == "__init__.py" and m.startswith(i + "."))}
             for m, deps in GRAPH.items()}
    assert _cycles(graph) == []


def test_the_checks_can_fail():
    """An upward import and a cycle, made up, are both caught."""
    made_up = {"rigfem.fe.model": {"rigfem.check"}, "rigfem.check": {"rigfem.fe.model"}}
    assert _upward(made_up) == ["rigfem.fe.model imports rigfem.check"]
    assert _cycles(made_up) == [["rigfem.check", "rigfem.fe.model"]]


@pytest.mark.parametrize("sub", SUBPACKAGES)
def test_public_api(sub):
    """Each subpackage names its API in ``__all__``, every name resolves, none is private."""
    mod = importlib.import_module(f"rigfem.{sub}")
    assert mod.__all__ and all(not n.startswith("_") for n in mod.__all__)
    for n in mod.__all__:
        assert getattr(mod, n) is not None


def test_modules_stay_small():
    """No module over 450 lines."""
    long = [str(f.relative_to(PKG)) for f in PKG.rglob("*.py") if len(f.read_text().splitlines()) > 450]
    assert long == []


#: what a kinematics or synthesis run must never load: the forces, the FE and the mesher
_HEAVY = ("rigfem.dynamics", "rigfem.fe", "rigfem.mesh", "skfem", "gmsh")


#: a scene file's schema names the fatigue vocabulary (rigfem.material): reading a scene loads
#: nothing of the verdict, FE or mesh code (only the verified cache, rigfem.mesh.cache, that
#: records a scene's content as validated)
_SCENE_HEAVY = ("rigfem.dynamics", "rigfem.mesh", "rigfem.fe", "rigfem.verdict", "skfem", "gmsh")
_CACHE_ONLY: list[str] = []  # the cache (rigfem.cache) is below them all


def _loaded_after(code: str, heavy: tuple[str, ...] = _HEAVY) -> list[str]:
    """The ``heavy`` modules in ``sys.modules`` after running ``code`` in a fresh interpreter."""
    probe = (f"import sys\n{code}\n"
             f"print(sorted(m for m in sys.modules "
             f"if any(m == h or m.startswith(h + '.') for h in {heavy!r})))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300,
                         env={**os.environ, "MPLBACKEND": "Agg"})
    assert out.returncode == 0, out.stderr
    return ast.literal_eval(out.stdout.strip().splitlines()[-1])


def test_kinematics_and_synthesis_load_no_dynamics():
    """A student's kinematics, turn analysis, synthesis and a scene's linkage need no forces."""
    code = """
import numpy as np
import rigfem.cli
from rigfem.linkage import fourbar_motion, fourbar_turn, inverted_slider_crank, linkage_motion
from rigfem.linkage import check_three_position, synthesize_function, three_position
m = fourbar_motion(540, 840, 780, 1020, np.arange(0, 360, 10.0))
t = fourbar_turn(540, 840, 780, 1020)
g = linkage_motion(inverted_slider_crank(500, 200, 100, masses=None), [0.0, 90.0], 6.28)
s = synthesize_function("x*log(x)", 1.0, 3.0, 20.0, 90.0, 80.0, 90.0, 2.0)
r = three_position(np.array([[0.0, 0.0], [-15.12, -9.0], [-29.128, -4.0]]), [-20.0, -35.0], [100.0, 200.0],
                   [30.0, 55.0])
check_three_position(r)
"""
    assert _loaded_after(code) == []


def test_a_scene_loads_as_plain_data():
    """Reading a scene and building its linkage computes no forces: no dynamics, mesh or FE model."""
    code = """
from rigfem.linkage import build, linkage_motion
from rigfem.scene import load_scene
for name in ("mech5-compressor", "mech3-inverted-slider-crank", "final-cm"):
    lk = build(load_scene(name))
linkage_motion(lk, [0.0, 90.0], 6.28)
"""
    assert _loaded_after(code, _SCENE_HEAVY) == _CACHE_ONLY


@pytest.mark.parametrize("argv", [
    ["kinematics", "--four-bar", "540", "840", "780", "1020", "--json"],
    ["kinematics", "--slider-crank", "100", "400", "--at", "30", "--json"],
    ["synthesize", "function", "x*log(x)", "--x", "1", "3", "--input", "20", "60", "--output", "80", "45",
     "--ground", "2"],
])
def test_cli_kinematics_loads_no_dynamics(argv):
    """``rigfem kinematics`` and ``rigfem synthesize`` (without --rig) run without the forces, FE or mesh."""
    code = f"""
import contextlib, io
from rigfem.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    assert main({argv!r}) == 0
"""
    assert _loaded_after(code) == []


def test_the_import_probe_can_fail():
    """The probe sees a dynamics import when there is one."""
    assert "rigfem.dynamics.solver" in _loaded_after("import rigfem.dynamics.solver")


def test_studies_aliases_warn_and_resolve():
    """Scripts written against rigfem.studies (before 0.2) still run, with a DeprecationWarning."""
    code = ("import warnings; warnings.simplefilter('error', DeprecationWarning)\n"
            "import rigfem.sweep\n"
            "try:\n    from rigfem.studies import SweepParams\nexcept DeprecationWarning as w: print(w)\n"
            "warnings.simplefilter('ignore')\n"
            "from rigfem.studies import SweepParams as A\nfrom rigfem.studies.closed_form import kt_plate_hole\n"
            "import rigfem.studies.sweep as s\n"
            "assert A is rigfem.sweep.SweepParams and s is __import__('rigfem.sweep.run').sweep.run\n"
            "print(kt_plate_hole(0.2) > 2)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "rigfem.studies.SweepParams moved to rigfem.sweep.configs.SweepParams" in out and out.endswith("True\n")


def test_the_pipeline_stages_take_at_most_four_parameters():
    """Every rigfem function that rigfem/pipeline.py composes takes at most four parameters (the
    previous product, its settings, the context and one more): a stage needing more wants a type."""
    import inspect

    import rigfem.pipeline as pipeline

    tree = ast.parse(pathlib.Path(pipeline.__file__).read_text())
    called = {ast.unparse(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
    stages = {}
    for name in called:
        obj = pipeline
        for part in name.split("."):
            obj = getattr(obj, part, None)
        if inspect.isfunction(obj) and obj.__module__.startswith("rigfem."):
            stages[f"{obj.__module__}.{obj.__qualname__}"] = len(inspect.signature(obj).parameters)
    assert len(stages) >= 8, stages  # read_job, linkage_state, the two react, part_cases, solve_cases, judge, ...
    assert {k: n for k, n in stages.items() if n > 4} == {}
