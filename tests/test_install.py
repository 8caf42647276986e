"""A regular (non-editable) install works from any folder: the wheel carries the part
definitions of geometry/, the rig reference they cite, and the built-in scenes."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_wheel_runs_from_another_folder(tmp_path):
    """Build the wheel, install it alone into a folder and run ``rigfem parts`` and ``rigfem mesh``
    from another folder with it first on the path (the dependencies come from this environment)."""
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(wheels), str(ROOT)],
                   check=True, capture_output=True)
    wheel = next(wheels.glob("rigfem-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert "rigfem/geometry/rail_size25.toml" in names and "rigfem/scenes/final-cm.toml" in names
    docs = {p.name for p in (ROOT / "geometry").glob("*.md")}  # the rig reference the part files cite
    assert docs and docs <= {n.rpartition("/")[2] for n in names if n.startswith("rigfem/geometry/")}
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(site), str(wheel)],
                   check=True, capture_output=True)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {**os.environ, "PYTHONPATH": str(site)}
    where = subprocess.run([sys.executable, "-c", "import rigfem; print(rigfem.__file__)"], cwd=elsewhere,
                           env=env, capture_output=True, text=True, check=True).stdout
    assert where.startswith(str(site))
    parts = subprocess.run([sys.executable, "-m", "rigfem", "parts"], cwd=elsewhere, env=env,
                           capture_output=True, text=True)
    assert parts.returncode == 0 and "PF_4b_006" in parts.stdout and str(site) in parts.stdout
    mesh = subprocess.run([sys.executable, "-m", "rigfem", "mesh", "PF_4b_006", "--size", "12", "--out",
                           str(elsewhere / "plate.vtu")], cwd=elsewhere, env=env, capture_output=True, text=True)
    assert mesh.returncode == 0, mesh.stderr
    assert (elsewhere / "plate.vtu").stat().st_size > 0


def test_every_import_of_the_package_is_a_declared_dependency():
    """Every third-party module rigfem/ imports comes from a distribution pyproject.toml names
    directly (the import name may differ from the distribution's: yaml would be PyYAML):
    a fresh install gets all of them, none only through another package's extra."""
    import ast
    import re
    import tomllib
    from importlib.metadata import packages_distributions

    norm = lambda name: re.sub(r"[-_.]+", "-", name).lower()  # noqa: E731 - PEP 503
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    declared = {norm(re.match(r"[A-Za-z0-9_.-]+", d).group()) for d in deps}
    made_by = packages_distributions()
    missing = set()
    for path in (ROOT / "rigfem").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module else [])
            for top in {n.split(".")[0] for n in names} - set(sys.stdlib_module_names) - {"rigfem"}:
                if not {norm(d) for d in made_by.get(top, [])} & declared:
                    missing.add(f"{top} ({path.relative_to(ROOT)})")
    assert not missing, f"imported but not declared in pyproject.toml: {sorted(missing)}"


def test_every_subpackage_is_in_the_wheel():
    """pyproject.toml lists its packages by hand: a subpackage missing there is missing from a regular
    install (rigfem.sweep, .verification and .design were, after the split of rigfem.studies)."""
    import tomllib

    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "rigfem").rglob("__init__.py")
             if "__pycache__" not in p.parts and "geometry" not in p.parts}
    assert found - listed == set(), f"pyproject.toml [tool.setuptools] packages lacks {sorted(found - listed)}"
