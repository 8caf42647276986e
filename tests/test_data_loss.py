"""Issue 38, data loss: a file that appears at an output's path while a command runs is kept.

The output is checked before any computation (absent, or a file rigfem wrote with --force); the
final rename must not replace what appeared there since (the user saving a file of that name,
another rigfem run writing the same path): the run is refused (exit 2), the file untouched and
nothing of the run left behind."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

import rigfem.cli.outputs as outputs
from rigfem.cli import main
from said import one_line

USER = "the user's own file, saved while rigfem ran\n"
FUNC = ["synthesize", "function", "x*log(x)", "--x", "1", "3", "--input", "20", "90", "--output", "80", "90",
        "--ground", "2"]
#: single-file outputs of each command, (id, argv with {} for the path, suffix); every one, --animate
#: and --scene-out too, goes through rigfem.cli.outputs.written (those two take half a minute here)
SINGLE = [
    ("kinematics-csv", ["kinematics", "--samples", "8", "--csv", "{}"], ".csv"),
    ("kinematics-plot", ["kinematics", "--samples", "8", "--plot", "{}"], ".png"),
    ("reactions-csv", ["reactions", "--csv", "{}"], ".csv"),
    ("reactions-plot", ["reactions", "--plot", "{}"], ".png"),
    ("mesh-out", ["mesh", "PF_4b_006", "--size", "12", "--out", "{}"], ".vtu"),
    ("synthesize-plot", [*FUNC, "--plot", "{}"], ".png"),
]


def _appearing(monkeypatch, target: Path, content: str | None = USER) -> None:
    """Make ``content`` appear at ``target`` (None: its rigfem content edited) once the command has
    written its output's temporary file, just before the final rename."""
    real = outputs.whole_file

    @contextlib.contextmanager
    def whole_file(path, *args, **kwargs):
        with real(path, *args, **kwargs) as tmp:
            yield tmp
            if Path(path) == target:
                target.write_text(content if content is not None else target.read_text() + "# edited\n")

    monkeypatch.setattr(outputs, "whole_file", whole_file)


def _left(folder: Path) -> list[str]:
    return [p.name for p in folder.rglob("*") if ".tmp" in p.name or p.name.endswith(".lock")]


@pytest.mark.parametrize("argv, suffix", [c[1:] for c in SINGLE], ids=[c[0] for c in SINGLE])
def test_a_file_that_appears_during_the_run_is_kept(tmp_path, capsys, monkeypatch, argv, suffix):
    monkeypatch.chdir(tmp_path)
    target = tmp_path / f"out{suffix}"
    _appearing(monkeypatch, target)
    code = main([a.replace("{}", str(target)) for a in argv])
    err = capsys.readouterr().err
    assert code == 2 and "appeared" in one_line(err) and str(target) in err and "wrote" not in err, err
    assert target.read_text() == USER
    assert _left(tmp_path) == []


def test_force_keeps_a_rigfem_file_edited_during_the_run(tmp_path, capsys, monkeypatch):
    target = tmp_path / "k.csv"
    assert main(["kinematics", "--samples", "8", "--csv", str(target)]) == 0
    capsys.readouterr()
    _appearing(monkeypatch, target, None)
    assert main(["kinematics", "--samples", "9", "--csv", str(target), "--force"]) == 2
    assert "appeared (or changed)" in one_line(capsys.readouterr().err)
    assert target.read_text().endswith("# edited\n") and target.read_text().count("\n") == 8 + 2
    assert _left(tmp_path) == []


def test_two_runs_writing_one_path_do_not_both_write(tmp_path):
    """Two processes started together on the same --csv: both find it free at their start; the
    one that finishes second must not replace the first one's file (both said 'wrote' before)."""
    target = tmp_path / "k.csv"
    cmd = [sys.executable, "-m", "rigfem", "kinematics", "--samples", "300000", "--csv", str(target)]
    runs = [subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            for _ in range(2)]
    done = [(p.wait(timeout=600), p.stderr.read()) for p in runs]
    wrote = [e for c, e in done if c == 0 and "rigfem: wrote" in e]
    refused = [e for c, e in done if c == 2]
    assert len(wrote) == 1 and len(refused) == 1, done
    assert "appeared" in one_line(refused[0]) or "already exists" in one_line(refused[0])
    assert sum(1 for _ in target.open()) == 300_001 and _left(tmp_path) == []


def test_no_replace_rename_refuses_an_existing_name(tmp_path):
    from rigfem.files import rename_new, whole_file

    (tmp_path / "a").write_text("new")
    (tmp_path / "b").write_text("old")
    with pytest.raises(FileExistsError):
        rename_new(tmp_path / "a", tmp_path / "b")
    assert (tmp_path / "b").read_text() == "old" and (tmp_path / "a").read_text() == "new"
    with pytest.raises(FileExistsError), whole_file(tmp_path / "b", replace=False) as tmp:
        tmp.write_text("newer")
    assert (tmp_path / "b").read_text() == "old" and sorted(os.listdir(tmp_path)) == ["a", "b"]
