"""Every script beside the package (benchmarks/, tools/, examples/) compiles, and every name it
imports from rigfem exists, in its own code and in the child scripts it runs (string constants
holding Python): a renamed or removed name breaks a published benchmark command at once, not when
someone next runs it (five benchmarks stayed broken for a day after the pipeline moved).

Only the imports are checked here, quickly; what the scripts compute is checked by the tests that
run them."""

from __future__ import annotations

import ast
import importlib
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted(p for d in ("benchmarks", "tools", "examples") for p in (ROOT / d).glob("*.py"))


def _child_scripts(tree: ast.AST) -> list[str]:
    """The string constants that are Python scripts importing rigfem (what a script runs in a child)."""
    return [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)
            and ("\nfrom rigfem" in n.value or "\nimport rigfem" in n.value)]


def _submodule(module, name: str) -> bool:
    return hasattr(module, "__path__") and importlib.util.find_spec(f"{module.__name__}.{name}") is not None


def missing_names(tree: ast.AST) -> list[str]:
    """``module.name`` for every rigfem import of ``tree`` that does not resolve."""
    out = []
    for n in ast.walk(tree):
        if isinstance(n, ast.ImportFrom) and n.level == 0 and n.module and n.module.split(".")[0] == "rigfem":
            try:
                module = importlib.import_module(n.module)
            except ImportError:
                out.append(n.module)
                continue
            for a in n.names:
                if a.name != "*" and not hasattr(module, a.name) and not _submodule(module, a.name):
                    out.append(f"{n.module}.{a.name}")
        elif isinstance(n, ast.Import):
            for a in n.names:
                if a.name.split(".")[0] == "rigfem":
                    try:
                        importlib.import_module(a.name)
                    except ImportError:
                        out.append(a.name)
    return out


def test_the_check_finds_a_missing_name_and_a_broken_child():
    bad = ast.parse('CHILD = """\nimport json\nfrom rigfem.pipeline import load_cases, no_such_stage\n"""\n'
                    "from rigfem.no_such_module import x\n")
    assert missing_names(bad) == ["rigfem.no_such_module"]
    assert missing_names(ast.parse(_child_scripts(bad)[0])) == ["rigfem.pipeline.no_such_stage"]


@pytest.mark.parametrize("path", SCRIPTS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_script_compiles_and_its_rigfem_imports_exist(path):
    tree = ast.parse(path.read_text(), str(path))  # a SyntaxError fails the test, naming the line
    missing = missing_names(tree)
    for i, child in enumerate(_child_scripts(tree)):
        missing += [f"{m} (in child script {i + 1})" for m in missing_names(ast.parse(child, f"{path}:child{i + 1}"))]
    assert not missing, f"{path.relative_to(ROOT)} imports names rigfem does not have: {', '.join(missing)}"
