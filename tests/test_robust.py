"""Issue 24 §1, §2, §4, §6: cost estimates before the expensive step, meshing that stops at
once on a signal, distributed runs that fail fast, and the cache environment."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rigfem.errors import InputError

RIGFEM = [sys.executable, "-m", "rigfem"]


def _env(tmp_path: Path, **extra: str) -> dict[str, str]:
    (tmp_path / "tmp").mkdir(exist_ok=True)
    return {**os.environ, "RIGFEM_CACHE": str(tmp_path / "cache"), "TMPDIR": str(tmp_path / "tmp"), **extra}


def _descendants(pid: int) -> set[int]:
    """Process ids below ``pid`` (from /proc)."""
    parent = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                parent[int(d.name)] = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                pass
    out, todo = set(), [pid]
    while todo:
        p = todo.pop()
        kids = {c for c, pp in parent.items() if pp == p}
        out |= kids
        todo += kids
    return out


# ----------------------------------------------------------------------------- §2 interruptions
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_during_meshing_ends_within_seconds(tmp_path, sig, code):
    """A fine rail (about 200k tets, minutes of gmsh) is interrupted while gmsh meshes: the run
    ends within 2 s (bound 10 s on a busy machine), with 130/143, and leaves nothing behind."""
    out = tmp_path / "rail.vtu"
    proc = subprocess.Popen([*RIGFEM, "mesh", "rail_size25", "--size", "4", "--no-cache", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path, env=_env(tmp_path))
    deadline = time.time() + 60
    while len(_descendants(proc.pid)) < 2 and time.time() < deadline and proc.poll() is None:
        time.sleep(0.05)  # the forkserver and the mesher process below it: gmsh has started
    assert proc.poll() is None, proc.communicate()[1]
    assert len(_descendants(proc.pid)) >= 2, "meshing never started in a child process"
    time.sleep(2.0)  # inside gmsh's meshing
    kids = _descendants(proc.pid)
    t0 = time.perf_counter()
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    delay = time.perf_counter() - t0
    print(f"{signal.Signals(sig).name}: exited {proc.returncode} after {delay:.2f} s")
    assert proc.returncode == code, err
    assert delay < 10.0
    assert b"Traceback" not in err and len(err.decode().strip().splitlines()) == 1
    time.sleep(0.5)
    assert not [k for k in kids if Path(f"/proc/{k}").exists()
                and (Path(f"/proc/{k}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z")]
    assert not out.exists()
    assert list((tmp_path / "tmp").iterdir()) == []  # no temporary files or folders
    cache = tmp_path / "cache"
    assert not cache.exists() or not [p for p in cache.rglob("*") if p.is_file()]


# ----------------------------------------------------------------------------- §1 cost estimates
def test_100_m_rail_refused_from_its_dimensions_before_gmsh(monkeypatch):
    import gmsh

    from rigfem.mesh import MeshSettings, mesh_part
    from rigfem.rig import load_part

    def no_gmsh(*a, **k):
        raise AssertionError("gmsh was initialised before the estimate refused")

    monkeypatch.setattr(gmsh, "initialize", no_gmsh)
    part = load_part("rail_size25", {"length": 100_000})
    t0 = time.perf_counter()
    with pytest.raises(InputError) as e:
        mesh_part(part, MeshSettings(6.0), use_cache=False)
    assert time.perf_counter() - t0 < 5.0
    msg = str(e.value)
    assert "\n" not in msg and "tets" in msg and "GiB" in msg and "s of meshing" in msg
    assert "machine's" in msg and "--allow-large" in msg
    assert not gmsh.isInitialized()


def test_100_m_rail_cli_exit_2_in_seconds(tmp_path):
    t0 = time.perf_counter()
    r = subprocess.run([*RIGFEM, "mesh", "rail_size25", "--length", "100000", "--out", str(tmp_path / "r.vtu")],
                       capture_output=True, text=True, env=_env(tmp_path), timeout=60)
    took = time.perf_counter() - t0
    print(f"100 m rail refused in {took:.2f} s: {r.stderr.strip()}")
    assert r.returncode == 2 and took < 15.0
    assert len(r.stderr.strip().splitlines()) == 1 and "GiB" in r.stderr and "--allow-large" in r.stderr


def test_allow_large_lifts_the_limit(tmp_path, monkeypatch):
    """The same request is refused on a tiny machine and meshed with the override."""
    from rigfem.mesh import MeshSettings, mesh_part
    from rigfem.rig import load_part
    from rigfem.settings import ALLOW_LARGE_ENV

    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))
    part = load_part("PF_4b_006")
    with pytest.raises(InputError, match="at least about"):  # from the dimensions, before gmsh
        mesh_part(part, MeshSettings(12.0), use_cache=False, machine_gib=1e-7)
    monkeypatch.setenv(ALLOW_LARGE_ENV, "1")
    pm = mesh_part(part, MeshSettings(12.0), use_cache=False, machine_gib=1e-7)
    assert len(pm.tets) > 0 and pm.meta["estimate_tets"] > 0
