"""Light commands import only what they use: ``rigfem --help``/``--version``/``check --help``,
``rigfem parts`` and ``rigfem kinematics`` of one linkage load no FE, mesh, plotting, interpolation,
cluster or scene-schema code (issue 26).

A test on imports, not on time (the time is a benchmark: ``python benchmarks/bench_perf.py --rows light``).
"""

import subprocess
import sys
from pathlib import Path

import pytest

import rigfem

#: modules a light command must not import: the FE stack, MKL, gmsh, plotting, JIT, the cluster,
#: interpolation, and pydantic (the scene schema: only for a scene's content not validated before)
HEAVY = ("scipy.sparse.linalg", "scipy.interpolate", "skfem", "gmsh", "pypardiso", "matplotlib", "pyvista",
         "numba", "dask", "pydantic", "pydantic_core")


def heavy(mods: set[str]) -> list[str]:
    """The modules of ``mods`` that are (or are inside) a :data:`HEAVY` one."""
    return sorted(m for m in mods if any(m == h or m.startswith(h + ".") for h in HEAVY))


def imported(*args: str) -> set[str]:
    """Every module ``python -X importtime -m rigfem ARGS`` imported (it must exit 0)."""
    return printed_and_imported(*args)[1]


def printed_and_imported(*args: str) -> tuple[str, set[str]]:
    """What ``python -X importtime -m rigfem ARGS`` printed and every module it imported (it must exit 0)."""
    r = subprocess.run([sys.executable, "-X", "importtime", "-m", "rigfem", *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-500:]
    return r.stdout, {ln.rsplit("|", 1)[1].strip() for ln in r.stderr.splitlines() if ln.startswith("import time:")}


@pytest.mark.parametrize("args", [("--help",), ("--version",), ("check", "--help"), ("mesh", "--help"),
                                  ("kinematics", "--four-bar", "300", "720", "480", "840", "--at", "30")])
def test_light_command_imports_no_heavy_module(args):
    mods = imported(*args)
    assert "rigfem.cli" in mods  # the measurement works
    assert not heavy(mods), f"rigfem {' '.join(args)} imported {heavy(mods)[:8]}"


def test_help_imports_no_numpy():
    """The command list needs only each subcommand's one-line help."""
    assert "numpy" not in imported("--help")


def test_parts_computes_volumes_once(tmp_path, monkeypatch):
    """``rigfem parts`` builds each solid in gmsh once; later runs read the cached volumes (no gmsh)."""
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))
    assert "gmsh" in imported("parts")  # first run: OpenCASCADE volumes
    mods = imported("parts")
    assert not heavy(mods), f"rigfem parts (cached volumes) imported {heavy(mods)[:8]}"
    assert "numpy" not in mods  # the cache reads a volume without numpy (40 ms of a 0.3 s command)
    assert (tmp_path / "rigfem-entries" / "volumes").is_dir()


def test_a_scene_is_validated_once_per_content(tmp_path, monkeypatch):
    """``rigfem kinematics SCENE`` validates the scene's content with the schema (pydantic) on the
    first read, then reads the same content without pydantic and prints the same; content
    changed in any byte is validated again, and an invalid scene is refused every time."""
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))
    args = ("kinematics", "mech2-fourbar-coupler-point", "--at", "30", "--json")
    first, mods = printed_and_imported(*args)
    assert "pydantic" in mods   # first read: the schema validates it
    again, mods = printed_and_imported(*args)
    assert "rigfem.scene" in mods and not heavy(mods), f"a validated scene imported {heavy(mods)[:8]}"
    assert again == first and '"crank_deg": 30.0' in first
    assert "pydantic" in imported("kinematics", "mech1-slider-crank")    # another scene: validated
    text = (Path(rigfem.__file__).parent / "scenes" / "mech2-fourbar-coupler-point.toml").read_text()
    edited = tmp_path / "edited.toml"
    edited.write_text(text.replace("b2 = 36.0", "b2 = 36.5"))
    assert "pydantic" in imported("kinematics", str(edited))
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("b2 = 36.0", "b2 = 5.0"))
    for _ in range(2):
        r = subprocess.run([sys.executable, "-m", "rigfem", "kinematics", str(bad)], capture_output=True, text=True)
        assert r.returncode == 2 and r.stdout == ""
        assert r.stderr.startswith("rigfem: error: scene 'bad.toml': [linkage].b2 = 5.0:"), r.stderr


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
