"""The one cache (rigfem.cache): keyed by the whole package, removing only what rigfem wrote, never
fatal when an entry vanishes, and its folder and limit read once at the edge."""

from __future__ import annotations

import json
import logging
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

import rigfem
from rigfem.cache import ENTRIES, Cache, from_environment, package_hash
from rigfem.cli import main
from rigfem.errors import InputError

RIGFEM = [sys.executable, "-m", "rigfem"]
PKG = Path(rigfem.__file__).resolve().parent


def _env(tmp_path: Path, **extra: str) -> dict[str, str]:
    (tmp_path / "tmp").mkdir(exist_ok=True)
    return {**os.environ, "RIGFEM_CACHE": str(tmp_path / "cache"), "TMPDIR": str(tmp_path / "tmp"), **extra}


def _blob(d: Path) -> None:
    (d / "x.bin").write_bytes(os.urandom(1000))


# ----------------------------------------------------------------------------- keyed by the package
def _hash_of_copy(root: Path) -> str:
    code = "import rigfem.cache as c; print(c.__file__, c.package_hash())"
    out = subprocess.run([sys.executable, "-c", code], env={**os.environ, "PYTHONPATH": str(root)}, cwd=root,
                         capture_output=True, text=True, check=True).stdout.split()
    assert out[0].startswith(str(root))  # the copy was imported, not the installed package
    return out[1]


@pytest.mark.parametrize("edit", ["rig/catalogue.py", "geometry/rail_size25.toml", "templates/report.html.j2",
                                  "report/views.py"])
def test_changing_any_file_of_the_package_changes_every_key(tmp_path, edit):
    """No hand-kept list of source files: an edit anywhere in a copy of the package (code, a part
    file, a template, a module no key named before) gives another package hash, so every entry of
    the edited package is another entry."""
    root = tmp_path / "copy"
    shutil.copytree(PKG, root / "rigfem", symlinks=False, ignore=shutil.ignore_patterns("__pycache__"))
    before = _hash_of_copy(root)
    assert before == package_hash()
    f = root / "rigfem" / edit
    f.write_bytes(f.read_bytes() + b"\n")
    after = _hash_of_copy(root)
    assert after != before
    cache = Cache(tmp_path / "c", 10**9)
    assert cache.entry_folder("meshes", {"a": 1}).name == Cache(tmp_path / "c", 10**9).entry_folder(
        "meshes", {"a": 1}).name  # the same inputs, the same key: the package is what changed it


def test_an_entry_of_another_package_is_not_read(tmp_path, monkeypatch, caplog):
    cache = Cache(tmp_path, 10**9)
    assert cache.put("t", {"a": 1}, lambda d: (d / "x.txt").write_text("1"))
    monkeypatch.setattr("rigfem.cache.package_hash", lambda: "another")  # the package as edited
    assert cache.get("t", {"a": 1}, lambda e: e.text("x.txt")) is None  # its key is another folder


# ----------------------------------------------------------------------------- only what rigfem wrote
def test_clear_removes_only_signed_entries_never_the_root_or_a_neighbour(tmp_path, capsys, monkeypatch):
    """``RIGFEM_CACHE=~/.cache rigfem cache --clear`` must not touch another program's data: a
    folder with its own manifest.json, a file beside the entries, an entry folder that holds a
    file of someone else's, the root itself."""
    root = tmp_path / "dot-cache"
    other = root / "other-app" / "item"
    other.mkdir(parents=True)
    (other / "manifest.json").write_text('{"files": {}}')  # someone else's manifest
    (root / "notes.txt").write_text("mine")
    cache = Cache(root, 10**9)
    for i in range(3):
        assert cache.put("meshes", {"i": i}, _blob)
    intruded = cache.entry_folder("meshes", {"i": 2})
    (intruded / "user.txt").write_text("put here by hand")  # an entry that holds something else
    monkeypatch.setenv("RIGFEM_CACHE", str(root))
    monkeypatch.delenv("RIGFEM_CACHE_MAX_GB", raising=False)
    assert main(["cache"]) == 0
    assert "meshes: 2 entries" in capsys.readouterr().out
    assert main(["cache", "--clear"]) == 0
    assert re.search(r"removed 2 entries, 2(\.\d+)? kB", capsys.readouterr().out)
    assert (other / "manifest.json").is_file() and (root / "notes.txt").read_text() == "mine"
    assert (intruded / "user.txt").is_file() and root.is_dir()
    assert sorted(p.name for p in (root / ENTRIES / "meshes").iterdir()) == [intruded.name]


def test_eviction_removes_least_recently_used_signed_entries_only(tmp_path):
    cache = Cache(tmp_path, 2600)  # two entries of about 1.2 kB fit
    foreign = tmp_path / ENTRIES / "meshes" / "foreign"
    foreign.mkdir(parents=True)
    (foreign / "manifest.json").write_text(json.dumps({"files": {"x.bin": "0"}}))  # unsigned: not rigfem's
    (foreign / "x.bin").write_bytes(os.urandom(5000))
    assert cache.put("meshes", {"n": "a"}, _blob) and cache.put("meshes", {"n": "b"}, _blob)
    a, b = (cache.entry_folder("meshes", {"n": n}) for n in "ab")
    now = time.time()
    os.utime(a / "manifest.json", (now - 100, now - 100))
    os.utime(b / "manifest.json", (now - 50, now - 50))
    assert cache.get("meshes", {"n": "a"}, lambda e: e.bytes("x.bin")) is not None  # a read: most recently used
    assert cache.put("meshes", {"n": "c"}, _blob)
    assert a.exists() and cache.entry_folder("meshes", {"n": "c"}).exists() and not b.exists()
    assert foreign.is_dir() and sum(e[1] for e in cache.entries()) <= 2600


def test_a_vanished_entry_is_computed_again_never_fatal(tmp_path, monkeypatch):
    """Another process clears the cache between a job's look and its read: the job computes it."""
    cache = Cache(tmp_path, 10**9)
    assert cache.put("t", {"a": 1}, lambda d: (d / "x.txt").write_text("1"))

    def read_after_a_clear(entry):
        Cache(tmp_path, 10**9).clear()  # e.g. `rigfem cache --clear` in another terminal
        return entry.text("x.txt")

    assert cache.get("t", {"a": 1}, read_after_a_clear) is None
    value, stored = cache.cached("t", {"a": 1}, lambda: "2", lambda v, d: (d / "x.txt").write_text(v),
                                 lambda e: e.text("x.txt"))
    assert (value, stored) == ("2", False)


def test_damaged_entry_is_discarded_and_logged(tmp_path, caplog):
    cache = Cache(tmp_path, 10**9)
    assert cache.put("t", {"a": 1}, lambda d: (d / "x.txt").write_text("right"))
    (cache.entry_folder("t", {"a": 1}) / "x.txt").write_text("wrong")
    with caplog.at_level(logging.WARNING, logger="rigfem.cache"):
        assert cache.get("t", {"a": 1}, lambda e: e.text("x.txt")) is None
    assert "discarded" in caplog.text and not cache.entry_folder("t", {"a": 1}).exists()


# ----------------------------------------------------------------------------- the environment, once
@pytest.mark.parametrize("raw", ["abc", "-1", "0", "nan", "inf", "1e7"])
def test_bad_limit_is_refused_whether_the_cache_is_warm_or_cold(tmp_path, monkeypatch, capsys, raw):
    """One rule, checked at start: a bad RIGFEM_CACHE_MAX_GB is bad input (exit 2, one line naming
    it) in every command, with an empty cache as with a warm one."""
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))
    monkeypatch.setenv("RIGFEM_CACHE_MAX_GB", raw)
    with pytest.raises(InputError, match="RIGFEM_CACHE_MAX_GB"):
        from_environment()
    assert Cache(tmp_path, 10**9).put("t", {"a": 1}, _blob)  # warm now
    for argv in (["cache"], ["kinematics", "--four-bar", "540", "840", "780", "1020", "--at", "10"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "RIGFEM_CACHE_MAX_GB" in err and len(err.strip().splitlines()) == 1


def test_default_limit_follows_the_free_disk(tmp_path, monkeypatch):
    from rigfem.cache import DEFAULT_GB

    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))
    monkeypatch.delenv("RIGFEM_CACHE_MAX_GB", raising=False)
    free = shutil.disk_usage(tmp_path).free / 1e9
    gb = from_environment().max_bytes / 1e9
    assert DEFAULT_GB[0] <= gb <= DEFAULT_GB[1]
    assert gb == pytest.approx(min(max(0.25 * free, DEFAULT_GB[0]), DEFAULT_GB[1]), rel=0.05)
    monkeypatch.setenv("RIGFEM_CACHE_MAX_GB", "0.5")
    assert from_environment().max_bytes == 5 * 10**8


@pytest.mark.parametrize("where", ["file", "proc"])
def test_unusable_cache_folder_runs_without_a_cache_and_says_so_once(tmp_path, where):
    cache = tmp_path / "cache-file" if where == "file" else Path("/proc/rigfem-cache-test")
    if where == "file":
        cache.write_text("a user's file\n")
    r = subprocess.run([*RIGFEM, "mesh", "PF_4b_006", "--size", "12", "--out", str(tmp_path / "p.vtu")],
                       capture_output=True, text=True, env=_env(tmp_path, RIGFEM_CACHE=str(cache)), timeout=300)
    assert r.returncode == 0, r.stderr
    said = [x for x in r.stderr.splitlines() if "running without a cache" in x]
    assert len(said) == 1 and str(cache) in said[0]
    assert (tmp_path / "p.vtu").stat().st_size > 0
    if where == "file":
        assert cache.read_text() == "a user's file\n"


def test_arrays_key_an_entry_by_their_content(tmp_path):
    """An array among an entry's inputs keys it by its bytes, dtype and shape (not numpy's abridged
    text, which would make large arrays that differ in the middle the same key); a numpy scalar by its value."""
    import numpy as np

    cache = Cache(tmp_path / "c", 10**9)
    a = np.zeros(5000)
    b = a.copy()
    b[2500] = 1.0
    assert str(a) == str(b)  # what json.dumps(default=str) used to key them by
    folders = {cache.entry_folder("t", {"x": x}) for x in (a, b, a.astype(np.float32), a.reshape(50, 100))}
    assert len(folders) == 4
    assert cache.entry_folder("t", {"x": a}) == cache.entry_folder("t", {"x": a.copy()})
    assert cache.entry_folder("t", {"x": np.float32(1.5)}) == cache.entry_folder("t", {"x": 1.5})
    with pytest.raises(TypeError, match="Python objects"):
        cache.entry_folder("t", {"x": np.array([object()])})
