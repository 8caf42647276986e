"""Issue 38, the environment and the terminal: nothing about the machine a command runs on is an
internal error.  An output encoding without σ gets ASCII; a closed stdout or stderr leaves the
result standing; a full disk (here: the file-size limit) is "could not write PATH", exit 3; a
name longer than the file system takes is bad input naming the option, a legal long name works;
result folders get the umask's permissions; a cache folder inside --out is refused naming both."""

from __future__ import annotations

import io
import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rigfem.cli import main
from rigfem.errors import InputError
from said import one_line, said

RIGFEM = [sys.executable, "-m", "rigfem"]
FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--no-pictures",
        "--quiet"]
SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _run(args: list[str], tmp_path: Path, env: dict | None = None, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([*RIGFEM, *args], capture_output=True, text=True, cwd=tmp_path, timeout=600,
                          env={**os.environ, **(env or {})}, **kw)


def _left(folder: Path) -> list[str]:
    return [p.name for p in folder.rglob("*") if ".tmp" in p.name or ".old" in p.name or p.name.endswith(".lock")]


# ----------------------------------------------------------------------------- encoding
@pytest.mark.parametrize("argv, words", [(["--help"], "sigma_u/2"), (["check", "--help"], "sigma_u/2"),
                                         (["kinematics", "--samples", "8"], "rad/s^2")])
def test_an_ascii_terminal_gets_ascii(tmp_path, argv, words):
    r = _run(argv, tmp_path, {"PYTHONIOENCODING": "ascii"})
    assert r.returncode == 0 and words in r.stdout and "Traceback" not in r.stderr, r.stderr
    r.stdout.encode("ascii")


@SETTINGS
@given(name=st.text(st.characters(blacklist_categories=("Cs", "Cc"), blacklist_characters="/\\"), min_size=1,
                    max_size=40).filter(lambda s: s not in (".", "..") and not s.startswith("-")))
def test_any_scene_name_prints_on_an_ascii_terminal(tmp_path_factory, monkeypatch, name):
    """The scene's name (its file's) heads the table: in any script, the ASCII stream shows it."""
    from rigfem.scene import builtin_scenes

    folder = tmp_path_factory.mktemp("scene")
    scene = folder / f"{name}.toml"
    scene.write_bytes(builtin_scenes()["final-cm"].read_bytes())
    out = io.TextIOWrapper(io.BytesIO(), encoding="ascii")
    monkeypatch.setattr(sys, "stdout", out)
    code = main(["kinematics", str(scene), "--samples", "8"])
    out.flush()
    text = out.buffer.getvalue().decode("ascii")
    assert code == 0 and "alpha=0 rad/s^2" in text


def test_a_c_locale_without_utf8_checks_and_writes_the_report(tmp_path):
    env = {"LC_ALL": "C", "LANG": "C", "PYTHONCOERCECLOCALE": "0", "PYTHONUTF8": "0", "PYTHONIOENCODING": ""}
    r = _run(["check", "final-cm", *FAST, "--out", "res"], tmp_path, env)
    assert r.returncode == 0 and "sigma_vm" in r.stdout, r.stderr
    assert "σu" in (tmp_path / "res" / "report.md").read_text(encoding="utf-8")


# ----------------------------------------------------------------------------- closed streams
@pytest.mark.parametrize("fd", [1, 2])
def test_a_closed_stdout_or_stderr_leaves_the_result(tmp_path, fd):
    r = subprocess.run([*RIGFEM, "check", "final-cm", *FAST, "--out", "res"], cwd=tmp_path, timeout=600,
                       capture_output=False, stdout=subprocess.DEVNULL if fd == 2 else None,
                       stderr=subprocess.PIPE if fd == 1 else None, text=True,
                       preexec_fn=lambda: os.close(fd))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "res" / "report.json").is_file() and _left(tmp_path) == []
    if fd == 1:
        assert said(r.stderr)[-1].startswith("rigfem: wrote res")


# ----------------------------------------------------------------------------- a full disk
def _file_limit(limit: int):
    return lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))


def test_a_full_disk_is_could_not_write_naming_the_file(tmp_path):
    r = _run(["kinematics", "--samples", "100000", "--csv", "big.csv"], tmp_path, preexec_fn=_file_limit(1 << 20))
    assert r.returncode == 3, r.stderr
    line = one_line(r.stderr)
    assert line.startswith(f"rigfem: could not write {tmp_path / 'big.csv'}: ") and str(tmp_path) in line
    assert "internal error" not in line and os.listdir(tmp_path) == []


def test_a_full_disk_during_a_check_names_the_result_folder(tmp_path):
    r = _run(["check", "final-cm", *FAST, "--out", "res"], tmp_path, {"RIGFEM_CACHE": str(tmp_path / "cache")},
             preexec_fn=_file_limit(1 << 17))  # 128 KiB: below a picture (compressed VTUs can be smaller)
    assert r.returncode == 3, r.stderr
    line = said(r.stderr)[-1]
    assert line.startswith("rigfem: could not write") and "res" in line and "internal error" not in r.stderr
    assert not (tmp_path / "res").exists() and _left(tmp_path) == []


# ----------------------------------------------------------------------------- names
@SETTINGS
@given(stem=st.text(st.characters(blacklist_categories=("Cs", "Cc"), blacklist_characters="/\\\x00"), min_size=1,
                    max_size=140).filter(lambda s: s not in (".", "..")))
@example(stem="x" * 247)   # 251 bytes: legal, its temporary sibling's name must stay short
@example(stem="é" * 130)   # 264 bytes: more than the file system takes
def test_a_name_is_written_if_it_fits_else_refused_naming_the_option(tmp_path_factory, capsys, stem):
    folder = tmp_path_factory.mktemp("names")
    path = folder / f"{stem}.csv"
    code = main(["kinematics", "--samples", "8", "--csv", str(path)])
    err = capsys.readouterr().err
    if len(os.fsencode(path.name)) <= 255:
        assert code == 0 and path.is_file(), err
    else:
        assert code == 2 and one_line(err).startswith("rigfem: error: --csv = ") and "bytes" in err, err
    assert _left(folder) == []


@pytest.mark.parametrize("length, ok", [(250, True), (255, True), (256, False), (260, False)])
def test_a_legal_long_result_folder_works_and_a_longer_one_is_bad_input(tmp_path, length, ok):
    from rigfem.report.folder import atomic_dir, check_writable, folder_lock

    out = tmp_path / ("r" * length)
    if not ok:
        with pytest.raises(InputError, match=f"--out = .*is {length} bytes, more than the 255"):
            check_writable(out, False)
        return
    with folder_lock(out), atomic_dir(out) as d:
        (d / "report.json").write_text("{}")
    assert (out / "report.json").is_file() and _left(tmp_path) == []


@pytest.mark.parametrize("cmd", [["check", "final-cm", *FAST], ["sweep", "--quiet"], ["convergence", "plate_A"],
                                 ["verify", "final-cm"], ["mesh", "PF_4b_006"]])
def test_an_output_name_too_long_is_exit_2_naming_the_option(tmp_path, capsys, monkeypatch, cmd):
    monkeypatch.chdir(tmp_path)
    code = main([*cmd, "--out", str(tmp_path / ("o" * 260 + (".vtu" if cmd[0] == "mesh" else "")))])
    assert code == 2 and "--out = " in one_line(capsys.readouterr().err)


@SETTINGS
@given(name=st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), min_size=1,
                    max_size=400).filter(lambda s: not s.startswith("-")))
def test_any_scene_argument_is_computed_or_bad_input_never_an_internal_error(capsys, name):
    from rigfem.scene import builtin_scenes

    code = main(["kinematics", name, "--samples", "8"])
    err = capsys.readouterr().err
    assert code == (0 if name in builtin_scenes() else 2) and "internal error" not in err, err


# ----------------------------------------------------------------------------- umask
@pytest.mark.parametrize("mask", [0o022, 0o027, 0o077, 0o002])
def test_a_result_folder_gets_the_umasks_permissions(tmp_path, mask):
    from rigfem.report.folder import atomic_dir

    old = os.umask(mask)
    try:
        with atomic_dir(tmp_path / "res") as d:
            (d / "report.json").write_text("{}")
    finally:
        os.umask(old)
    assert (tmp_path / "res").stat().st_mode & 0o777 == 0o777 & ~mask


# ----------------------------------------------------------------------------- the cache inside --out
@pytest.mark.parametrize("cmd", [["check", "final-cm", *FAST], ["sweep", "--quiet"], ["verify", "final-cm"],
                                 ["convergence", "plate_A"]])
@pytest.mark.parametrize("where", ["cache inside out", "out inside cache"])
def test_a_cache_folder_inside_out_is_refused_naming_both(tmp_path, capsys, monkeypatch, cmd, where):
    out, cache = tmp_path / "res", tmp_path / "res" / "cache"
    if where == "out inside cache":
        out, cache = cache / "res", tmp_path / "res"
    (cache / "meshes" / "abc").mkdir(parents=True)
    (cache / "meshes" / "abc" / "mesh.npz").write_bytes(b"cached")
    monkeypatch.setenv("RIGFEM_CACHE", str(cache))
    monkeypatch.chdir(tmp_path)
    code = main([*cmd, "--out", str(out), "--force"])
    line = one_line(capsys.readouterr().err)
    assert code == 2 and str(out) in line and str(cache) in line and "RIGFEM_CACHE" in line, line
    assert (cache / "meshes" / "abc" / "mesh.npz").read_bytes() == b"cached"


def test_a_long_temporary_folder_still_meshes(tmp_path):
    """TMPDIR past what a Unix socket's path holds: the mesher's children are spawned, not forked from a
    forkserver whose socket cannot be made (it was 'could not compute: ... AF_UNIX path too long')."""
    tmp = tmp_path / ("t" * (100 - len(str(tmp_path))))
    tmp.mkdir()
    r = _run(["mesh", str(Path(__file__).parents[1] / "examples" / "plate_with_hole.geo"), "--fidelity", "draft", "--out", "p.vtu"],
             tmp_path, env={"TMPDIR": str(tmp)})
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "p.vtu").is_file()
