"""The package's structure: layers import one way only, no import cycles, a curated public API.

Layers follow the data path (configuration -> reactions -> part load cases -> mesh -> solution
-> verdict -> report); a module may import its own layer and the layers below, never above.
"""

import ast
import importlib
import pathlib

import pytest

import rigfem

PKG = pathlib.Path(rigfem.__file__).parent
#: lowest first; every rigfem module belongs to exactly one layer
LAYERS = [
    ("rigfem.errors", "rigfem.material", "rigfem.settings", "rigfem.geometry"),  # geometry: part files (data)
    ("rigfem.rig",),
    ("rigfem.dynamics",),
    ("rigfem.loads",),
    ("rigfem.mesh",),
    ("rigfem.fe",),
    ("rigfem.verdict",),
    ("rigfem.report",),
    ("rigfem.io",),
    ("rigfem.schema", "rigfem.scene"),
    ("rigfem.check",),
    ("rigfem.studies",),
    ("rigfem.cli", "rigfem.__main__"),
]
SUBPACKAGES = ("rig", "dynamics", "loads", "mesh", "fe", "verdict", "report", "io", "studies")


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
    """No module over 600 lines without a reason written at its top."""
    long = [str(f.relative_to(PKG)) for f in PKG.rglob("*.py")
            if len(f.read_text().splitlines()) > 600 and "Why this module is long" not in f.read_text()[:3000]]
    assert long == []
