"""Result folders are written atomically and never silently overwritten."""

import pytest

from rigfem.errors import InputError
from rigfem.report import MARKER, atomic_dir


def test_atomic_dir_commits_on_success(tmp_path):
    out = tmp_path / "res"
    with atomic_dir(out) as d:
        (d / "a.txt").write_text("1")
        assert not out.exists()
    assert (out / "a.txt").read_text() == "1"
    assert [p.name for p in tmp_path.iterdir()] == ["res"]


def test_atomic_dir_leaves_nothing_on_failure(tmp_path):
    out = tmp_path / "res"
    with pytest.raises(RuntimeError):
        with atomic_dir(out) as d:
            (d / "a.txt").write_text("1")
            raise RuntimeError("solver blew up")
    assert list(tmp_path.iterdir()) == []


def test_existing_needs_force(tmp_path):
    out = tmp_path / "res"
    with atomic_dir(out) as d:  # a folder rigfem wrote (it carries the marker)
        (d / "old.txt").write_text("old")
    with pytest.raises(InputError, match="--force"):
        with atomic_dir(out):
            pass
    assert (out / "old.txt").exists()
    with atomic_dir(out, force=True) as d:
        (d / "new.txt").write_text("new")
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "new.txt"]
