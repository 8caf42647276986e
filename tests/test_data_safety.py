"""No result and no user file is ever lost: --force replaces only rigfem's folders, an
interrupted run leaves nothing behind, a second run on the same folder is refused."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

from rigfem.cli import main
from rigfem.report import MARKER, atomic_dir, folder_lock

FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"]


def test_force_never_replaces_a_user_folder(tmp_path, capsys):
    mine = tmp_path / "thesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("years of work")
    assert main(["check", "final-cm", "--out", str(mine), "--force", *FAST]) == 2
    err = capsys.readouterr().err
    assert "not a rigfem result folder" in err and err.count("\n") == 1
    assert (mine / "chapter1.tex").read_text() == "years of work"


def test_force_replaces_a_rigfem_folder(tmp_path):
    out = tmp_path / "r"
    with atomic_dir(out) as d:
        (d / "old.txt").write_text("old")
    assert (out / MARKER).is_file()
    with atomic_dir(out, force=True) as d:
        (d / "new.txt").write_text("new")
    assert (out / "new.txt").is_file() and not (out / "old.txt").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]  # no temporary or old folder left


def test_failed_block_leaves_nothing(tmp_path):
    out = tmp_path / "r"
    try:
        with atomic_dir(out) as d:
            (d / "half.vtu").write_text("half")
            raise KeyboardInterrupt
    except KeyboardInterrupt:
        pass
    assert list(tmp_path.iterdir()) == []


def test_second_run_on_the_same_folder_is_refused(tmp_path, capsys):
    out = tmp_path / "r"
    lock = tmp_path / ".r.lock"
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        lock.write_text(f"{holder.pid}\n")  # a live run holds the folder
        assert main(["check", "final-cm", "--out", str(out), *FAST]) == 2
        assert "being written by another rigfem run" in capsys.readouterr().err
        assert not out.exists()
    finally:
        holder.kill()
        holder.wait()
    with folder_lock(out):  # the lock of a dead process is taken over
        assert lock.read_text().strip() == str(os.getpid())
    assert not lock.exists()


def test_sigterm_leaves_nothing_behind(tmp_path):
    out = tmp_path / "r"
    proc = subprocess.Popen([sys.executable, "-m", "rigfem", "check", "final-cm", "--out", str(out),
                             "--parts", "crank_rail", "--fidelity", "draft", "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)
    deadline = time.time() + 60
    while not (tmp_path / ".r.lock").exists() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.05)
    time.sleep(1.0)  # inside the computation
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert b"Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # no result, no temporary folder, no lock


def test_gmsh_does_not_take_over_sigterm(tmp_path):
    """gmsh's initialisation installs C signal handlers that kill the process on SIGTERM; the
    session puts Python's back, so a run terminated while meshing still cleans up."""
    code = ("import os, signal, sys, time\n"
            "from rigfem.mesh.geometry import gmsh_session\n"
            "def h(s, f): raise SystemExit(7)\n"
            "signal.signal(signal.SIGTERM, h)\n"
            "with gmsh_session():\n"
            "    os.kill(os.getpid(), signal.SIGTERM)\n"
            "    time.sleep(5)\n")
    # run elsewhere than the repository: its rigfem/ folder must not shadow a regular install
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=60, cwd=tmp_path)
    assert proc.returncode == 7, proc.stderr
