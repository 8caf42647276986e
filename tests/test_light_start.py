"""Light commands import only what they use: ``rigfem --help``/``--version``/``check --help`` and
``rigfem kinematics`` of one linkage load no FE, mesh, plotting or cluster code (issue 26).

A test on imports, not on time (the time is a benchmark: ``python benchmarks/bench_perf.py --rows light``).
"""

import subprocess
import sys

import pytest

#: modules a light command must not import: the FE stack, MKL, gmsh, plotting, JIT, the cluster
HEAVY = ("scipy.sparse.linalg", "skfem", "gmsh", "pypardiso", "matplotlib", "pyvista", "numba", "dask")


def imported(*args: str) -> set[str]:
    """Every module ``python -X importtime -m rigfem ARGS`` imported (it must exit 0)."""
    r = subprocess.run([sys.executable, "-X", "importtime", "-m", "rigfem", *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-500:]
    return {ln.rsplit("|", 1)[1].strip() for ln in r.stderr.splitlines() if ln.startswith("import time:")}


@pytest.mark.parametrize("args", [("--help",), ("--version",), ("check", "--help"), ("mesh", "--help"),
                                  ("kinematics", "--four-bar", "300", "720", "480", "840", "--at", "30")])
def test_light_command_imports_no_heavy_module(args):
    mods = imported(*args)
    assert "rigfem.cli" in mods  # the measurement works
    heavy = sorted(m for m in mods if m.split(".")[0] in HEAVY or m in HEAVY or m.startswith("scipy.sparse.linalg"))
    assert not heavy, f"rigfem {' '.join(args)} imported {heavy[:8]}"


def test_help_imports_no_numpy():
    """The command list needs only each subcommand's one-line help."""
    assert "numpy" not in imported("--help")


def test_parts_computes_volumes_once(tmp_path, monkeypatch):
    """``rigfem parts`` builds each solid in gmsh once; later runs read the cached volumes (no gmsh)."""
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))
    assert "gmsh" in imported("parts")  # first run: OpenCASCADE volumes
    mods = imported("parts")
    heavy = sorted(m for m in mods if m.split(".")[0] in HEAVY)
    assert not heavy, f"rigfem parts (cached volumes) imported {heavy[:8]}"
    assert (tmp_path / "volumes").is_dir()


def test_a_command_imports_only_its_own_module():
    """``rigfem parts`` builds the parser of its own subcommand only, and reads the installed
    version (importlib.metadata) only for ``--version``."""
    code = ("import sys\nfrom rigfem.cli import main\nmain(['parts'])\n"
            "print(sorted(m for m in sys.modules if m.startswith('rigfem.cli.')), 'importlib.metadata' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-500:]
    assert r.stdout.splitlines()[-1] == "['rigfem.cli.exitcodes', 'rigfem.cli.parts', 'rigfem.cli.progress'] False"
    r = subprocess.run([sys.executable, "-m", "rigfem", "--version"], capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.startswith("rigfem 0.") and r.stderr == ""
