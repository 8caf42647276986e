"""Bad input of every kind ends in exit 2 with one line naming the field, no traceback and
nothing written; any scene or CSV either parses or gives exit 2 (hypothesis)."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigfem.cli import main
from rigfem.errors import InputError
from rigfem.scene import builtin_scenes
from said import one_line, said

BASE = tomllib.loads(builtin_scenes()["final-cm"].read_text())
FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"]


def _toml(v) -> str:
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml(x)}" for k, x in v.items()) + "}"
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, float) and v != v:
        return "nan"
    if isinstance(v, float) and abs(v) == float("inf"):
        return "inf" if v > 0 else "-inf"
    return repr(v)


def dump(d: dict) -> str:
    top = [f"{k} = {_toml(v)}" for k, v in d.items() if not isinstance(v, dict)]
    tables = [f"[{k}]\n" + "\n".join(f"{kk} = {_toml(vv)}" for kk, vv in v.items())
              for k, v in d.items() if isinstance(v, dict)]
    return "\n".join(top + tables) + "\n"


def _set(table: str, key: str, value):
    def f(d):
        d.setdefault(table, {})[key] = value
    return f


def _pop(table: str, key: str):
    return lambda d: d[table].pop(key)


#: (id, mutation of final-cm, text the message names)
SCENES = [
    ("chek-table", lambda d: d.update(chek={"order": 2}), "did you mean 'check'"),
    ("linkag-table", lambda d: d.update(linkag={}), "did you mean 'linkage'"),
    ("order-true", _set("check", "order", True), "[check].order"),
    ("order-3", _set("check", "order", 3), "[check].order"),
    ("order-str", _set("check", "order", "2"), "[check].order"),
    ("order-float", _set("check", "order", 2.0), "[check].order"),
    ("orde-key", _set("check", "orde", 2), "did you mean 'order'"),
    ("rails-str", _set("linkage", "rails_mm", [700, "a", 1000]), "[linkage].rails_mm[1]"),
    ("rails-short", _set("linkage", "rails_mm", [700]), "[linkage].rails_mm"),
    ("rails-tiny", _set("linkage", "rails_mm", [700, 1, 1000]), "[linkage].rails_mm[1]"),
    ("rails-nan", _set("linkage", "rails_mm", [700, float("nan"), 1000]), "[linkage].rails_mm[1]"),
    ("b2-nan", _set("linkage", "b2", float("nan")), "[linkage].b2"),
    ("b2-inf", _set("linkage", "b2", float("inf")), "[linkage].b2"),
    ("b2-neg", _set("linkage", "b2", -480.0), "[linkage].b2"),
    ("b2-metres", _set("linkage", "b2", 0.48), "[linkage].b2"),
    ("b2-huge", _set("linkage", "b2", 1e9), "[linkage].b2"),
    ("b2-str", _set("linkage", "b2", "480"), "[linkage].b2"),
    ("b2-bool", _set("linkage", "b2", True), "[linkage].b2"),
    ("b2-list", _set("linkage", "b2", [480]), "[linkage].b2"),
    ("b2-missing", _pop("linkage", "b2"), "[linkage].b2"),
    ("d-table", _set("linkage", "d", {"x": 1}), "[linkage].d"),
    ("type-bad", _set("linkage", "type", "fourbar"), "[linkage].type"),
    ("type-missing", _pop("linkage", "type"), "[linkage].type"),
    ("type-int", _set("linkage", "type", 4), "[linkage].type"),
    ("masses-bad", _set("linkage", "masses", "heavy"), "[linkage].masses"),
    ("speed-zero", _set("linkage", "speed_hz", 0.0), "speed_hz"),
    ("speed-huge", _set("linkage", "speed_hz", 1e4), "[linkage].speed_hz"),
    ("speed-two", _set("linkage", "rpm", 60.0), "only one of"),
    ("branch-bad", _set("linkage", "branch", "left"), "[linkage].branch"),
    ("offset-on-fourbar", _set("linkage", "offset", 5.0), "[linkage].offset"),
    ("gas-on-fourbar", _set("linkage", "gas", {"p_N": 1.0}), "[linkage].gas"),
    ("bodies-with-rig", _set("linkage", "bodies", {"rod": {"mass_kg": 1.0}}), "masses = 'none'"),
    ("title-int", _set("linkage", "title", 5), "[linkage].title"),
    ("description-list", lambda d: d.update(description=["a"]), "description"),
    ("modes-empty", _set("check", "modes", []), "[check].modes"),
    ("modes-bad", _set("check", "modes", ["orginal"]), "[check].modes[0]"),
    ("modes-twice", _set("check", "modes", ["cycle", "cycle"]), "twice"),
    ("modes-str", _set("check", "modes", "cycle"), "[check].modes"),
    ("parts-empty", _set("check", "parts", []), "[check].parts"),
    ("parts-bad", _set("check", "parts", ["plate_Z"]), "[check].parts"),
    ("parts-int", _set("check", "parts", [1]), "[check].parts[0]"),
    ("fidelity-bad", _set("check", "fidelity", "ultra"), "[check].fidelity"),
    ("size-neg", _set("check", "size_mm", -1.0), "[check].size_mm"),
    ("size-nan", _set("check", "size_mm", float("nan")), "[check].size_mm"),
    ("local-above-size", lambda d: d["check"].update(size_mm=5.0, local_size_mm=8.0), "local_size_mm"),
    ("load-factor-zero", _set("check", "load_factor", 0.0), "[check].load_factor"),
    ("load-factor-inf", _set("check", "load_factor", float("inf")), "[check].load_factor"),
    ("limit-factor-2", _set("check", "limit_factor", 2.0), "[check].limit_factor"),
    ("ndir-float", _set("check", "bearing_directions", 8.5), "[check].bearing_directions"),
    ("ndir-big", _set("check", "bearing_directions", 1000), "[check].bearing_directions"),
    ("material-unknown", _set("check", "material", "unobtainium"), "unobtainium"),
    ("material-int", _set("check", "material", 5), "[check].material"),
    ("material-SI", _set("check", "material", {"name": "s", "E": 2.1e11, "nu": 0.3, "sigma_u": 470.0,
                                               "density": 7.85e-9}), "[check.material].E"),
    ("material-missing", _set("check", "material", {"name": "s"}), "[check.material]"),
    ("fatigue-surface", _set("check", "fatigue", {"surface": "polished"}), "[check.fatigue].surface"),
    ("fatigue-reliability", _set("check", "fatigue", {"reliability": 0.8}), "[check.fatigue].reliability"),
    ("fatigue-unknown", _set("check", "fatigue", {"surfce": "ground"}), "did you mean 'surface'"),
    ("samples-few", _set("check", "samples", 3), "[check].samples"),
    ("samples-float", _set("check", "samples", 360.5), "[check].samples"),
    ("frames-neg", _set("check", "frames", -1), "[check].frames"),
    ("mass-model-bad", _set("check", "mass_model", "newton"), "[check].mass_model"),
    ("csv-missing", _set("check", "reactions_csv", "nope.csv"), "[check].reactions_csv"),
    ("rule-broken", lambda d: d["linkage"].update(b2=540.0), "transmission angle"),
    ("off-grid", lambda d: d["linkage"].update(d=1021.0), "on the hole grid"),
]


def _one_line_exit_2(capsys, argv, out_dir) -> str:
    code = main(argv)
    cap = capsys.readouterr()
    assert code == 2, cap.err
    assert one_line(cap.err).startswith("rigfem: error: ")
    assert "Traceback" not in cap.err + cap.out
    assert not out_dir.exists()
    return cap.err


@pytest.mark.parametrize("mutate, field", [c[1:] for c in SCENES], ids=[c[0] for c in SCENES])
def test_bad_scene(tmp_path, capsys, mutate, field):
    d = copy.deepcopy(BASE)
    d["check"].update(parts=["plate_A"], modes=["original"], fidelity="draft", frames=0)
    mutate(d)
    scene = tmp_path / "s.toml"
    scene.write_text(dump(d))
    err = _one_line_exit_2(capsys, ["check", str(scene), "--out", str(tmp_path / "o"), "--quiet"], tmp_path / "o")
    assert field in err


RAW = [
    ("syntax", "[linkage\ntype =", "not valid TOML"),
    ("binary", b"\x00\x01\x02\xff", "binary"),
    ("latin1", "description = \"caf\xe9\"\n".encode("latin-1"), "not UTF-8"),
    ("deep", "a = " + "[" * 500 + "]" * 500 + "\n", "nested too deeply"),
    ("deep-tables", "a = " + "{b = " * 20 + "1" + "}" * 20 + "\n", "nested too deeply"),
    ("empty", "", "[linkage]"),
    ("dup-key", '[linkage]\ntype = "four-bar"\ntype = "four-bar"\n', "not valid TOML"),
    ("control-char", 'description = "a\x1b[31m"\n', "not valid TOML"),
]


@pytest.mark.parametrize("text, field", [c[1:] for c in RAW], ids=[c[0] for c in RAW])
def test_unreadable_scene(tmp_path, capsys, text, field):
    scene = tmp_path / "s.toml"
    (scene.write_bytes if isinstance(text, bytes) else scene.write_text)(text)
    err = _one_line_exit_2(capsys, ["check", str(scene), "--out", str(tmp_path / "o"), *FAST], tmp_path / "o")
    assert field in err


#: (id, check options, text the message names)
OPTIONS = [
    ("modes-empty", ["--modes", ""], "[check].modes"),
    ("modes-comma", ["--modes", ","], "[check].modes"),
    ("parts-empty", ["--parts", ""], "[check].parts"),
    ("parts-unknown", ["--parts", "plate_Q"], "[check].parts"),
    ("parts-typo", ["--parts", "plate_a"], "did you mean 'plate_A'"),
    ("order-0", ["--order", "0"], "[check].order"),
    ("size-nan", ["--size", "nan"], "[check].size_mm"),
    ("size-inf", ["--size", "inf"], "[check].size_mm"),
    ("local-size-0", ["--local-size", "0"], "[check].local_size_mm"),
    ("samples-0", ["--samples", "0"], "[check].samples"),
    ("frames-big", ["--frames", "100000"], "[check].frames"),
    ("no-scene", ["no-such-scene"], "neither a file nor a built-in scene"),
    ("csv-missing", ["--reactions-csv", "/nonexistent/r.csv"], "reactions_csv"),
    ("rule-broken", ["final-nc"], "transmission angle"),
]


@pytest.mark.parametrize("args, field", [c[1:] for c in OPTIONS], ids=[c[0] for c in OPTIONS])
def test_bad_check_option(tmp_path, capsys, args, field):
    argv = ["check", *([] if args[0] in ("no-such-scene", "final-nc") else ["final-cm"]), *args,
            "--out", str(tmp_path / "o"), "--quiet"]
    err = _one_line_exit_2(capsys, argv, tmp_path / "o")
    assert field in err


def test_unwritable_out_is_refused_before_computing(capsys):
    """A folder nobody may write in, root included: the kernel checks /proc/sys's permissions
    itself (mode 0555) without the override root has elsewhere, so this runs as root in CI too."""
    o = Path("/proc/sys/rigfem-o")
    err = _one_line_exit_2(capsys, ["check", "final-cm", "--out", str(o), *FAST], o)
    assert "is under /proc, a system folder" in err


def test_out_under_a_file_is_refused(tmp_path, capsys):
    f = tmp_path / "f"
    f.write_text("mine")
    err = _one_line_exit_2(capsys, ["check", "final-cm", "--out", str(f / "o"), *FAST], f / "o")
    assert "is not a folder" in err and f.read_text() == "mine"


def test_out_is_a_file(tmp_path, capsys):
    f = tmp_path / "f"
    f.write_text("mine")
    code = main(["check", "final-cm", "--out", str(f), "--force", *FAST])
    err = capsys.readouterr().err
    assert code == 2 and "not a folder" in err and f.read_text() == "mine"


# ----------------------------------------------------------------------------- reactions CSV
def _csv(tmp_path, rows: list[str], head: str = "crank_deg,O2_fx_N,O2_fy_N,A_fx_N,A_fy_N,B_fx_N,B_fy_N,"
         "O4_fx_N,O4_fy_N,torque_Nm") -> str:
    p = tmp_path / "r.csv"
    p.write_text(head + "\n" + "\n".join(rows) + "\n")
    return str(p)


def _turn(step: float = 5.0, scale: float = 1.0, angle=lambda a: a, amp: float = 400.0) -> list[str]:
    import numpy as np

    rows = []
    for a in np.arange(0.0, 360.0, step):
        f = amp * scale * (1.2 + np.cos(np.radians(a)))
        rows.append(f"{angle(a):.10g}," + ",".join(f"{f:.6g}" for _ in range(8)) + ",10")
    return rows


CSVS = [
    ("half-turn", lambda t: _csv(t, _turn()[:36]), "full turn"),
    ("sparse-30deg", lambda t: _csv(t, _turn(30.0)), "full turn"),
    ("radians-in-deg-column", lambda t: _csv(t, _turn(angle=lambda a: a * 3.14159265 / 180)), "radians"),
    ("degrees-in-rad-column", lambda t: _csv(t, _turn(), head="crank_rad,O2_fx_N,O2_fy_N,A_fx_N,A_fy_N,B_fx_N,"
                                                                "B_fy_N,O4_fx_N,O4_fy_N,torque_Nm"), "degrees"),
    ("kilonewton", lambda t: _csv(t, _turn(scale=1e-3)), "kN"),
    ("huge", lambda t: _csv(t, _turn(scale=1e5)), "above"),
    ("two-turns", lambda t: _csv(t, _turn() + [r.replace(r.split(",")[0], str(float(r.split(",")[0]) + 360), 1)
                                               for r in _turn()]), "more than one turn"),
    ("decreasing", lambda t: _csv(t, list(reversed(_turn()))), "increase"),
    ("text-cell", lambda t: _csv(t, _turn()[:-1] + ["x,1,1,1,1,1,1,1,1,1"]), "non-numeric"),
    ("nan-cell", lambda t: _csv(t, _turn()[:-1] + ["355,nan,1,1,1,1,1,1,1,1"]), "non-finite"),
    ("no-angle", lambda t: _csv(t, _turn(), head="phi,O2_fx_N,O2_fy_N,A_fx_N,A_fy_N,B_fx_N,B_fy_N,O4_fx_N,"
                                                  "O4_fy_N,torque_Nm"), "crank-angle column"),
    ("empty", lambda t: _csv(t, []), "no data rows"),
    ("ragged", lambda t: _csv(t, _turn()[:-1] + ["355,1,1"]), "columns"),
    ("sharp-peak", lambda t: _csv(t, [r if i != 20 else r.split(",")[0] + ",5000" * 8 + ",10"
                                      for i, r in enumerate(_turn())]), "too coarsely"),
]


@pytest.mark.parametrize("make, field", [c[1:] for c in CSVS], ids=[c[0] for c in CSVS])
def test_bad_reactions_csv(tmp_path, capsys, make, field):
    path = make(tmp_path)
    err = _one_line_exit_2(capsys, ["check", "final-cm", "--reactions-csv", path, "--out", str(tmp_path / "o"),
                                    *FAST], tmp_path / "o")
    assert field in err and "reaction CSV" in err


def test_good_csv_passes_the_import_checks(tmp_path):
    from rigfem.io import read_csv

    h = read_csv(_csv(tmp_path, _turn()))
    assert h.crank_deg.size == 72


# ----------------------------------------------------------------------------- other commands
OTHERS = [
    ("reactions-neg", ["reactions", "--four-bar", "-540", "840", "780", "1020"], "b2"),
    ("reactions-nan", ["reactions", "--four-bar", "nan", "840", "780", "1020"], "b2"),
    ("reactions-word", ["reactions", "--four-bar", "a", "840", "780", "1020"], "b2"),
    ("reactions-samples", ["reactions", "--four-bar", "540", "840", "780", "1020", "--samples", "0"], "samples"),
    ("reactions-speed", ["reactions", "--four-bar", "540", "840", "780", "1020", "--speed-hz", "inf"], "speed"),
    ("reactions-model", ["reactions", "--four-bar", "540", "840", "780", "1020", "--model", "x"], "model"),
    ("reactions-scene", ["reactions", "no-such-scene"], "scene"),
    ("mesh-unknown", ["mesh", "no_such_part", "--out", "{o}/m.vtu"], "no_such_part"),
    ("mesh-size", ["mesh", "plate_A", "--size", "-1", "--out", "{o}/m.vtu"], "size"),
    ("mesh-size-nan", ["mesh", "PF_4b_006", "--size", "nan", "--out", "{o}/m.vtu"], "size"),
    ("verify-fidelity", ["verify", "--fidelity", "ultra", "--out", "{o}"], "fidelity"),
    ("verify-peak-tol", ["verify", "--peak-tol", "x", "--out", "{o}"], "peak"),
    ("verify-scene", ["verify", "no-such-scene", "--out", "{o}"], "scene"),
    ("convergence-levels", ["convergence", "--levels", "99", "--out", "{o}"], "levels"),
    ("convergence-ratio", ["convergence", "--ratio", "nan", "--out", "{o}"], "ratio"),
    ("convergence-mode", ["convergence", "--mode", "sideways", "--out", "{o}"], "mode"),
    ("sweep-samples", ["sweep", "--samples", "1", "--out", "{o}"], "samples"),
    ("sweep-speed", ["sweep", "--speed-hz", "-1", "--out", "{o}"], "speed_hz"),
    ("sweep-fidelity", ["sweep", "--fidelity", "ultra", "--out", "{o}"], "fidelity"),
]


@pytest.mark.parametrize("argv, field", [c[1:] for c in OTHERS], ids=[c[0] for c in OTHERS])
def test_bad_input_other_commands(tmp_path, capsys, argv, field):
    o = tmp_path / "o"
    try:
        code = main([a.replace("{o}", str(o)) for a in argv])
    except SystemExit as exc:  # argparse refuses a malformed option itself (exit 2, one line)
        code = exc.code
    cap = capsys.readouterr()
    assert code == 2, cap.err
    assert len(said(cap.err)) == 1 and "Traceback" not in cap.err + cap.out
    assert field in cap.err.lower() or field in cap.err
    assert not o.exists()


# ----------------------------------------------------------------------------- properties
_values = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), st.floats(allow_nan=True),
                    st.text(max_size=8), st.lists(st.integers(-5, 2000), max_size=4))
_keys = st.sampled_from(["b2", "b3", "b4", "d", "type", "order", "modes", "parts", "size_mm", "rails_mm",
                         "speed_hz", "masses", "fidelity", "samples", "chek", "x"])


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(table=st.sampled_from(["linkage", "check"]), key=_keys, value=_values)
def test_any_scene_parses_or_is_input_error(tmp_path, table, key, value):
    """A scene with one field replaced by anything: a valid linkage and settings, or InputError."""
    from stages import job_of

    d = copy.deepcopy(BASE)
    if value is None:
        d[table].pop(key, None)
    else:
        d[table][key] = value
    scene = tmp_path / "p.toml"
    scene.write_text(dump(d))
    try:
        cs = job_of(scene, allow=True)
    except InputError as exc:
        assert "\n" not in str(exc)
        return
    assert cs.settings.order in (1, 2) and cs.linkage.meta["type"] == "four-bar"


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(step=st.floats(0.5, 60.0), scale=st.floats(1e-5, 1e7), start=st.floats(-720, 720),
       drop=st.integers(0, 100))
def test_any_csv_imports_or_is_input_error(tmp_path, step, scale, start, drop):
    """A reaction history of any sampling, scale and start: a finite history, or InputError."""
    import numpy as np

    from rigfem.io import read_csv

    rows = _turn(step, scale, angle=lambda a: a + start)
    rows = rows[: max(len(rows) - drop, 0)]
    try:
        h = read_csv(_csv(tmp_path, rows))
    except InputError as exc:
        assert "\n" not in str(exc)
        return
    assert np.all(np.diff(h.crank_deg) <= 10.0 + 1e-9)
    assert all(np.isfinite(j.force_N).all() for j in h.joints.values())


@pytest.mark.parametrize("L_mm", [600.0, 550.0])
def test_a_compressor_without_clearance_is_refused(tmp_path, capsys, L_mm):
    """[linkage.gas] whose cylinder head (L_mm − c_mm from the pivot) the piston reaches, 500 mm
    for crank 150 and rod 350 mm: the gas force would be unbounded (an inf reached the reactions
    table with exit 0); refused naming both lengths.  Just beyond the reach it runs."""
    text = (builtin_scenes()["mech5-compressor"]).read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("L_mm = 1000.0", f"L_mm = {L_mm}"))
    err = _one_line_exit_2(capsys, ["reactions", str(bad)], tmp_path / "none")
    assert f"L_mm - c_mm = {L_mm - 100:g} mm must exceed the piston's top dead centre" in err and "= 500 mm" in err
    bad.write_text(text.replace("L_mm = 1000.0", "L_mm = 600.5"))
    assert main(["reactions", str(bad)]) == 0
    out = capsys.readouterr().out
    assert "inf" not in out and "nan" not in out
