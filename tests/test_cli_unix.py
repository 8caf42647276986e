"""Issue 24 §3, §5, §7: one output policy for every command, text and numbers as users type them,
a CLI that behaves like a Unix tool.  Every bad input: exit 2, one line naming the field, no
traceback, no user file overwritten, nothing half-written."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigfem.cli import main
from rigfem.errors import InputError
from rigfem.linkage import parse_function
from said import said

FUNC = ["synthesize", "function", "x*log(x)", "--x", "1", "3", "--input", "20", "90", "--output", "80", "90",
        "--ground", "2"]
MOTION = ["synthesize", "motion", "--points", "0,0", "-15.12,-9", "-29.128,-4"]
FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"]
USER = "my own notes, not rigfem's\n"

#: (id, argv with {} where the output path goes, suffix of a file output or "/" for a folder)
OUTPUTS = [
    ("reactions-csv", ["reactions", "--csv", "{}"], ".csv"),
    ("reactions-plot", ["reactions", "--plot", "{}"], ".png"),
    ("kinematics-csv", ["kinematics", "--csv", "{}"], ".csv"),
    ("kinematics-plot", ["kinematics", "--plot", "{}"], ".png"),
    ("kinematics-animate", ["kinematics", "--animate", "{}"], ".gif"),
    ("mesh-out", ["mesh", "plate_A", "--out", "{}"], ".vtu"),
    ("synthesize-plot", [*FUNC, "--plot", "{}"], ".png"),
    ("synthesize-scene-out", [*MOTION, "--rig", "--no-stress", "--scene-out", "{}"], ".toml"),
    ("sweep-out", ["sweep", "--workers", "1", "--out", "{}"], "/"),
    ("verify-out", ["verify", "final-cm", "--out", "{}"], "/"),
    ("convergence-out", ["convergence", "plate_A", "--out", "{}"], "/"),
    ("check-out", ["check", "final-cm", *FAST, "--out", "{}"], "/"),
]


def _argv(argv: list[str], path: str, *extra: str) -> list[str]:
    return [a.replace("{}", path) for a in argv] + list(extra)


def _bad(capsys, argv: list[str], *needles: str) -> str:
    """Exit 2 with one error line naming ``needles``, no traceback."""
    code = main(argv)
    cap = capsys.readouterr()
    errors = said(cap.err)   # progress lines aside
    assert code == 2, cap.err
    assert len(errors) == 1 and errors[0].startswith("rigfem: error: "), cap.err
    assert "Traceback" not in cap.err + cap.out
    for n in needles:
        assert n in errors[0], errors[0]
    return errors[0]


def _user_target(tmp_path: Path, suffix: str) -> Path:
    """A user's own file (or folder with a file) where the output would go."""
    if suffix == "/":
        p = tmp_path / "mine"
        p.mkdir()
        (p / "notes.txt").write_text(USER)
    else:
        p = tmp_path / f"mine{suffix}"
        p.write_text(USER)
    return p


def _untouched(tmp_path: Path, target: Path) -> None:
    content = target / "notes.txt" if target.is_dir() else target
    assert content.read_text() == USER
    if target.is_dir():
        assert sorted(x.name for x in target.iterdir()) == ["notes.txt"]
    left = [p.name for p in tmp_path.rglob("*") if ".tmp" in p.name or p.name.endswith(".lock")]
    assert left == []


@pytest.mark.parametrize("argv, suffix", [c[1:] for c in OUTPUTS], ids=[c[0] for c in OUTPUTS])
def test_existing_user_output_is_never_overwritten(tmp_path, capsys, monkeypatch, argv, suffix):
    monkeypatch.chdir(tmp_path)
    target = _user_target(tmp_path, suffix)
    _bad(capsys, _argv(argv, str(target)), "already exists", "--force")
    _untouched(tmp_path, target)


@pytest.mark.parametrize("argv, suffix", [c[1:] for c in OUTPUTS], ids=[c[0] for c in OUTPUTS])
def test_force_replaces_only_what_rigfem_wrote(tmp_path, capsys, monkeypatch, argv, suffix):
    monkeypatch.chdir(tmp_path)
    target = _user_target(tmp_path, suffix)
    err = _bad(capsys, _argv(argv, str(target), "--force"), "--force")
    assert "rigfem" in err.split("error:", 1)[1]
    _untouched(tmp_path, target)


@pytest.mark.parametrize("argv, suffix", [c[1:] for c in OUTPUTS], ids=[c[0] for c in OUTPUTS])
def test_output_under_proc_is_refused(tmp_path, capsys, monkeypatch, argv, suffix):
    monkeypatch.chdir(tmp_path)
    _bad(capsys, _argv(argv, "/proc/rigfem-out" + ("" if suffix == "/" else suffix)), "/proc")


@pytest.mark.parametrize("argv, suffix", [c[1:] for c in OUTPUTS], ids=[c[0] for c in OUTPUTS])
def test_output_below_a_file_is_refused(tmp_path, capsys, monkeypatch, argv, suffix):
    monkeypatch.chdir(tmp_path)
    f = tmp_path / "afile.txt"
    f.write_text(USER)
    _bad(capsys, _argv(argv, str(f / ("o" + ("" if suffix == "/" else suffix)))), "not a folder")
    assert f.read_text() == USER


@pytest.mark.parametrize("argv, suffix", [c[1:] for c in OUTPUTS], ids=[c[0] for c in OUTPUTS])
def test_output_dot_is_refused(tmp_path, capsys, monkeypatch, argv, suffix):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "notes.txt").write_text(USER)
    _bad(capsys, _argv(argv, "."), "'.'")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]


def test_full_destination_is_refused(tmp_path, monkeypatch):
    import shutil

    from rigfem.cli.outputs import check_place

    monkeypatch.setattr(shutil, "disk_usage", lambda p: shutil._ntuple_diskusage(100, 99, 1))
    with pytest.raises(InputError, match="full"):
        check_place("--csv", tmp_path / "r.csv")


def test_force_replaces_a_file_rigfem_wrote_and_not_once_edited(tmp_path, capsys):
    out = tmp_path / "r.csv"
    assert main(["reactions", "--csv", str(out)]) == 0
    first = out.read_bytes()
    assert f"rigfem: wrote {out}" in capsys.readouterr().err
    assert (tmp_path / ".rigfem-outputs.json").is_file()
    assert main(["reactions", "--csv", str(out), "--force"]) == 0 and out.read_bytes() == first
    out.write_text(first.decode() + "# my note\n")
    capsys.readouterr()
    _bad(capsys, ["reactions", "--csv", str(out), "--force"], "not written by rigfem")
    assert out.read_text().endswith("# my note\n")


# ----------------------------------------------------------------------------- §5 expressions
POLES = [("1/(x-2)", "x = 2"), ("1/(x-2.0001)", "x = 2.0001"), ("tan(x)", "x = 1.5708"), ("log(x-2)", "x = 1"),
         ("sqrt(2-x)", "x = 2.001"), ("1/0", "x = 1"), ("x**1e5", "x = 1.008"), ("exp(exp(exp(x)))", "x = 1"),
         ("1/sin(pi*x)", "x = 1"), ("(x-2)**-2", "x = 2")]


@pytest.mark.parametrize("expr, where", POLES)
def test_pole_or_non_finite_value_names_the_x(capsys, expr, where):
    argv = list(FUNC)
    argv[2] = expr
    _bad(capsys, argv, "EXPR", where)


BAD_EXPR = [("", "empty"), ("x +* 2", "column"), ("__import__('os')", "EXPR"), ("x.real", "column"),
            ("foo(x)", "unknown function 'foo'"), ("y", "unknown name 'y'"), ("1e999*x", "overflows"),
            ("(" * 100 + "x" + ")" * 100, "at most 60"), ("x" + "**x" * 3000, "nests too deeply"),
            ("0" + "-" * 5000 + "x", "nests too deeply"), ("x*" * 6000, "characters long"), ("lambda: 1", "EXPR"),
            ("x if x else 1", "EXPR"), ("[x]", "EXPR")]


@pytest.mark.parametrize("expr, needle", BAD_EXPR, ids=[f"expr{i}" for i in range(len(BAD_EXPR))])
def test_bad_expression_is_one_line(capsys, expr, needle):
    argv = list(FUNC)
    argv[2] = expr
    _bad(capsys, argv, "EXPR", needle)


def test_long_expressions_parse():
    x = np.linspace(1, 2, 5)
    assert np.allclose(parse_function("+".join(["x"] * 3000))(x), 3000 * x)
    assert np.allclose(parse_function("x**-1 - -x^2 + 2**3**2")(x), 1 / x + x ** 2 + 512)


def test_result_far_beyond_useful_accuracy_is_flagged(capsys):
    argv = list(FUNC)
    argv[2], argv[4], argv[5] = "sin(5*x)", "0", "6"
    assert main(argv) == 1
    assert "DEFECT: accuracy defect" in capsys.readouterr().out


_ATOMS = st.sampled_from(["x", "2", "0.5", "pi", "e", "3e1", "(x+1)"])
_FUNCS = st.sampled_from(["sin", "cos", "exp", "sqrt", "abs", "tanh", "arctan"])
_OPS = {"+": np.add, "-": np.subtract, "*": np.multiply, "/": np.divide}


@st.composite
def _expression(draw, depth=0):
    """(text, numpy function) of a random valid expression."""
    kind = draw(st.integers(0, 2 if depth < 4 else 0))
    if kind == 0:
        a = draw(_ATOMS)
        vals = {"x": lambda x: x, "pi": lambda x: np.pi + 0 * x, "e": lambda x: np.e + 0 * x,
                "(x+1)": lambda x: x + 1}
        return a, vals.get(a, lambda x, a=a: float(a) + 0 * x)
    if kind == 1:
        name = draw(_FUNCS)
        t, f = draw(_expression(depth + 1))
        return f"{name}({t})", lambda x: getattr(np, name)(f(x))
    op = draw(st.sampled_from(list(_OPS)))
    (ta, fa), (tb, fb) = draw(_expression(depth + 1)), draw(_expression(depth + 1))
    return f"({ta}){op}({tb})", lambda x: _OPS[op](fa(x), fb(x))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_expression())
def test_parser_agrees_with_numpy(case):
    text, ref = case
    x = np.linspace(0.3, 2.7, 7)
    with np.errstate(all="ignore"):
        want = ref(x)
    got = parse_function(text)(x)
    assert np.allclose(got, want, equal_nan=True, rtol=1e-12, atol=0)


@settings(max_examples=80, deadline=None)
@given(st.text(alphabet="x0123456789.eE+-*/^()pisnqrtlogab ,_[]'\"\\", max_size=60))
def test_any_text_parses_or_is_one_input_error(text):
    try:
        f = parse_function(text)
    except InputError as exc:
        assert "\n" not in str(exc) and "EXPR" in str(exc)
        return
    assert f(np.array([1.0, 2.0])).shape == (2,)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr), st.text(max_size=12)))
def test_any_ground_length_text_is_accepted_or_refused_in_one_line(capsys, text):
    argv = list(FUNC)
    argv[argv.index("--ground") + 1] = text
    try:
        code = main(argv)
    except SystemExit as exc:   # argparse: a value that looks like an option
        code = exc.code
    cap = capsys.readouterr()
    assert "Traceback" not in cap.err and "internal error" not in cap.err
    assert code in (0, 1, 2, 3)
    if code == 2:
        assert len(said(cap.err)) == 1


# ----------------------------------------------------------------------------- §5 geometry
GEOMETRY = [
    (["synthesize", "motion", "--points", "0,0", "0,0", "1,1"], "coincide"),
    (["synthesize", "motion", "--points", "5,5", "1,2", "5,5"], "coincide"),
    (["synthesize", "motion", "--points", "0,0", "1e300,0", "1,1"], "--points X"),
    (["synthesize", "motion", "--points", "0,0", "1,inf", "1,1"], "--points Y"),
    ([*FUNC[:-1], "1e300"], "--ground"),
    ([*FUNC[:-1], "0"], "--ground"),
    (["reactions", "--four-bar", "1e300", "840", "780", "1020"], "b2"),
    (["reactions", "--four-bar", "540", "0", "780", "1020"], "B3"),
    (["kinematics", "--four-bar", "540", "840", "1e308", "1020"], "b4"),
    (["kinematics", "--slider-crank", "1e200", "1e201"], "b2"),
    (["kinematics", "--slider-crank", "300", "840", "--offset", "1e300"], "--offset"),
]


@pytest.mark.parametrize("argv, needle", GEOMETRY, ids=[f"geom{i}" for i in range(len(GEOMETRY))])
def test_absurd_geometry_is_one_line(capsys, argv, needle):
    _bad(capsys, argv, needle)


def test_kinematics_of_a_linkage_that_does_not_turn_fully(capsys):
    lk = ["kinematics", "--four-bar", "300", "300", "300", "500"]
    assert main([*lk, "--at", "300", "--json"]) == 0
    assert '"crank_deg": 300.0' in capsys.readouterr().out
    assert main([*lk, "--samples", "8"]) == 0
    out = capsys.readouterr().out
    assert "dead points" in out and "crank range 266.1774 to 453.8226 deg" in out
    _bad(capsys, [*lk, "--at", "180"], "--at = 180", "between 266.1774 and 453.8226", "dead points")


# ----------------------------------------------------------------------------- §5 files as others write them
def _reactions_csv(tmp_path: Path) -> Path:
    p = tmp_path / "r.csv"
    assert main(["reactions", "--csv", str(p)]) == 0
    return p


@pytest.mark.parametrize("encode", ["utf-8-sig-crlf", "utf-16", "utf-16-le-nobom", "cr-only"])
def test_text_files_as_other_programs_write_them(tmp_path, encode):
    from rigfem.io import read_csv

    p = _reactions_csv(tmp_path)
    text = p.read_text()
    blob = {"utf-8-sig-crlf": text.replace("\n", "\r\n").encode("utf-8-sig"), "utf-16": text.encode("utf-16"),
            "utf-16-le-nobom": text.encode("utf-16-le"), "cr-only": text.replace("\n", "\r").encode()}[encode]
    q = tmp_path / "other.csv"
    q.write_bytes(blob)
    a, b = read_csv(p), read_csv(q)
    assert np.array_equal(a.crank_deg, b.crank_deg) and np.array_equal(a.torque_Nm, b.torque_Nm)


@pytest.mark.parametrize("encode", ["utf-8-sig", "utf-16"])
def test_scene_files_as_other_programs_write_them(tmp_path, capsys, encode):
    from rigfem.scene import builtin_scenes

    text = builtin_scenes()["final-cm"].read_text().replace("\n", "\r\n")
    p = tmp_path / "s.toml"
    p.write_bytes(text.encode(encode))
    assert main(["reactions", str(p)]) == 0
    mine = capsys.readouterr().out
    assert main(["reactions", "final-cm"]) == 0
    assert capsys.readouterr().out == mine


@pytest.mark.parametrize("argv", [["reactions", "{}"], ["check", "{}", *FAST], ["kinematics", "{}"],
                                  ["check", "final-cm", *FAST, "--reactions-csv", "{}"]])
def test_binary_is_refused_as_binary(tmp_path, capsys, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    p = tmp_path / "blob.toml"
    p.write_bytes(bytes(range(256)) * 8)
    _bad(capsys, _argv(argv, str(p)), "binary")


def test_decode_text_refuses_latin1_in_one_line():
    from rigfem.errors import decode_text

    with pytest.raises(InputError, match="not UTF-8 or UTF-16"):
        decode_text("größe = 1\n".encode("latin-1"), "scene 'x'")


def test_geo_that_gmsh_cannot_parse_is_bad_input(tmp_path, capsys):
    geo = tmp_path / "bad.geo"
    geo.write_text("Point(1) = {0,0,0,1};\nPoint(2) = {1,0,0 1};\n")
    _bad(capsys, ["mesh", str(geo), "--out", str(tmp_path / "m.vtu")], "gmsh cannot read it", "line 2")
    assert not (tmp_path / "m.vtu").exists()


def test_step_that_gmsh_cannot_parse_is_bad_input(tmp_path, capsys):
    step = tmp_path / "bad.step"
    step.write_text("ISO-10303-21;\nHEADER;garbage\n")
    _bad(capsys, ["mesh", str(step), "--out", str(tmp_path / "m.vtu")], "gmsh cannot read it", "Line")


# ----------------------------------------------------------------------------- §7 a Unix tool
def _rigfem(*argv: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "rigfem", *argv], capture_output=True, text=True, timeout=300, **kw)


def test_version():
    r = _rigfem("--version")
    assert r.returncode == 0 and r.stdout.startswith("rigfem ")


def test_pipe_to_head_ends_quietly():
    r = subprocess.run(f"set -o pipefail; {sys.executable} -m rigfem kinematics --json --samples 4000 | head -1",
                       shell=True, executable="/bin/bash", capture_output=True, text=True, timeout=300)
    assert r.stdout == "{\n" and r.returncode == 141
    progress = re.compile(r"^rigfem kinematics: .* … \d+ s$")   # a busy machine may print a progress line
    assert [x for x in r.stderr.splitlines() if not progress.match(x)] == []


@pytest.mark.parametrize("cmd", ["check", "reactions", "kinematics", "convergence", "verify", "mesh", "sweep",
                                 "synthesize function", "synthesize motion", "parts", "show", "compare"])
def test_help_reads_as_text_with_every_default(capsys, cmd):
    with pytest.raises(SystemExit):
        main([*cmd.split(), "--help"])
    out = capsys.readouterr().out
    assert "{'" not in out and "[]" not in out and "(default: )" not in out
    import re

    for line in re.findall(r"^  --\S+ [A-Z_.]+\s+.*$", out, flags=re.M):
        assert line   # the formatter ran
    if cmd in ("check", "reactions", "kinematics", "verify", "convergence"):
        assert "final-cm" in out   # the same default configuration, named


def test_reactions_kinematics_and_check_default_to_the_same_configuration(capsys):
    assert main(["reactions", "--json"]) == 0
    r = capsys.readouterr().out
    assert main(["kinematics", "--json", "--samples", "8"]) == 0
    k = capsys.readouterr().out
    assert '"b2": 480' in r.replace(".0", "") and '"b2": 480' in k.replace(".0", "")


def test_progress_lines_when_not_a_terminal():
    import io
    import time

    from rigfem.cli.progress import heartbeat

    buf = io.StringIO()
    with heartbeat("verify", stream=buf, after_s=0.05, every_s=0.1, terminal=False):
        time.sleep(0.4)
    lines = buf.getvalue().splitlines()
    assert len(lines) >= 2 and all(re.fullmatch(r"rigfem verify: running … \d+ s", x) for x in lines)


def test_progress_lines_name_each_stage_once_the_command_is_long():
    import io
    import time

    from rigfem.cli.progress import heartbeat, stage

    buf = io.StringIO()
    with heartbeat("check", stream=buf, after_s=0.1, every_s=10, terminal=False):
        stage("dynamics")              # before after_s: quick commands print nothing
        time.sleep(1.0)
        stage("meshing part crank")    # after: a line as the stage begins
        stage("solving part crank")
    stage("report")                    # no command running: nothing
    lines = [re.sub(r"… \d+ s$", "… N s", x) for x in buf.getvalue().splitlines()]
    assert lines == ["rigfem check: dynamics … N s", "rigfem check: meshing part crank … N s",
                     "rigfem check: solving part crank … N s"]


def test_every_command_says_where_its_outputs_are(tmp_path, capsys):
    png = tmp_path / "k.png"
    assert main(["kinematics", "--samples", "8", "--plot", str(png)]) == 0
    assert said(capsys.readouterr().err) == [f"rigfem: wrote {png}"]


def test_interrupted_write_leaves_nothing(tmp_path, capsys, monkeypatch):
    import rigfem.cli.kinematics as kin

    def half(m, path):
        Path(path).write_text("crank_deg\n1\n")
        raise KeyboardInterrupt

    monkeypatch.setattr(kin, "write_csv", half)
    assert main(["kinematics", "--samples", "8", "--csv", str(tmp_path / "k.csv")]) == 130
    assert list(tmp_path.iterdir()) == []


def test_quiet_means_no_progress_lines_even_when_slow(tmp_path, monkeypatch, capsys):
    """--quiet silences the progress lines too, not only the bar: a slow machine's line would
    otherwise stand before the one-line error."""
    from rigfem.cli import main, progress

    monkeypatch.setattr(progress, "AFTER_S", 0.0)   # every command counts as long
    assert main(["sweep", "--scheduler", "tcp://127.0.0.1:70000", "--out", str(tmp_path / "s"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "[1, 65535]" in err[0]
