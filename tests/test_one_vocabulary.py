"""One vocabulary for a part, built-in or custom: the preset is the mesher's settings type, and
``rigfem mesh`` says where it refined and lists only the exit codes it can return."""

import dataclasses
import pathlib

import pytest

from rigfem.cli import build_parser, main
from rigfem.mesh import mesh_part
from rigfem.rig import load_part
from rigfem.settings import FIDELITY, MeshSettings, check_settings, preset

GEO = str(pathlib.Path(__file__).resolve().parents[1] / "examples" / "plate_with_hole.geo")


@pytest.fixture(autouse=True)
def cache_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))


def test_a_preset_is_the_mesh_settings_of_a_check():
    """The presets, a scene's [check] settings and the mesher share one type and its field names."""
    for name, p in FIDELITY.items():
        assert isinstance(p, MeshSettings) and preset(name) is p
        s = check_settings({"fidelity": name}, "four-bar")
        assert isinstance(s, MeshSettings) and s.key() == p.key()
        assert (s.order, s.bearing_directions) == (p.order, p.bearing_directions)
    over = check_settings({"fidelity": "draft", "size_mm": 7.0}, "four-bar")
    assert (over.size_mm, over.local_size_mm) == (7.0, FIDELITY["draft"].local_size_mm)
    assert {f.name for f in dataclasses.fields(MeshSettings)} >= {"size_mm", "local_size_mm"}


def test_a_preset_meshes_a_custom_part():
    pm = mesh_part(load_part(GEO), preset("draft").refined(("hole",)))
    assert pm.meta["settings"]["size_mm"] == 8.0 and pm.meta["settings"]["local_size_mm"] == 1.7
    assert pm.meta["settings"]["refine"] == ["hole"]


def test_mesh_says_which_surfaces_it_refined(tmp_path, capsys):
    out = str(tmp_path / "m.vtu")
    assert main(["mesh", GEO, "--fidelity", "standard", "--refine", "hole", "--out", out]) == 0
    said = capsys.readouterr().out
    assert "global size 6 mm (standard preset)" in said and "refined on hole to 1.2 mm" in said
    assert main(["mesh", GEO, "--out", out, "--force"]) == 0   # replaces the file rigfem wrote
    said = capsys.readouterr().out
    assert "no surface refined" in said and "nowhere" not in said


def test_mesh_names_the_curved_surfaces_meshed_finer(tmp_path, capsys):
    """Curvature sizing refines the plate's small screw holes even when --refine is not given."""
    assert main(["mesh", "PF_4b_006", "--out", str(tmp_path / "p.vtu")]) == 0
    said = capsys.readouterr().out
    assert "finer by curvature on screw_1" in said and "screw_2" in said and "nowhere" not in said


def _epilog(command: str) -> str:
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return sub.choices[command].epilog


def test_mesh_help_lists_only_its_exit_codes():
    mesh, check = _epilog("mesh"), _epilog("check")
    assert "0 mesh written" in mesh and "2 bad input" in mesh and "3 could not compute" in mesh
    assert "1 a part fails" not in mesh and "passes" not in mesh
    assert "0 every part passes, 1 a part fails" in check


def test_mesh_local_size_above_size_is_bad_input(tmp_path, capsys):
    rc = main(["mesh", GEO, "--size", "4", "--local-size", "5", "--out", str(tmp_path / "m.vtu")])
    assert rc == 2 and "--local-size" in capsys.readouterr().err


# One vocabulary for what a configuration is (issue 40 §3): it *assembles* (closes over a full turn),
# it *meets the rig rules* (geometry/RIG.md §2), it *passes the stress criterion* (σu/2) — never "mountable".
ROOT = pathlib.Path(__file__).resolve().parents[1]
FINAL_NC = ROOT / "results" / "final-nc"


def test_mountable_is_not_a_word_of_rigfem():
    """Nowhere in the package, the docs or the README; the sweep table's legacy column name aside."""
    files = [*ROOT.joinpath("rigfem").rglob("*.*"), *ROOT.joinpath("docs").rglob("*.md"), ROOT / "README.md",
             ROOT / "geometry/RIG.md"]
    found = [f"{f.relative_to(ROOT)}: {line.strip()}" for f in files if f.suffix in (".py", ".j2", ".js", ".toml", ".md")
             for line in f.read_text(encoding="utf-8").splitlines() if "mountable" in line.lower()
             and '"on_the_hole_grid": "mountable"' not in line and 'formerly "mountable"' not in line]
    assert found == []


def test_the_check_report_says_the_three_things_apart():
    """A configuration that breaks a rig rule but passes on stress: FAIL overall, beside the stress
    criterion's own PASS, in the Markdown, the HTML and the command line."""
    import json

    from rigfem.cli.check import _summary
    from rigfem.report.document import render_markdown
    from rigfem.report.html import render_html

    r = json.loads((FINAL_NC / "report.json").read_text())
    said = "the configuration assembles; does not meet the rig rules; passes the stress criterion"
    md = render_markdown(r)
    assert f"**Overall verdict: FAIL** — {said}." in md and "Stress criterion: **PASS** — peak von Mises" in md
    assert "does not meet the rig rules (geometry/RIG.md §2)" in md and "cannot be mounted" not in md
    html = render_html(r, FINAL_NC)
    assert said in html and 'Stress criterion <span class="badge pass">PASS</span>' in html
    assert "DOES NOT MEET THE RIG RULES" in html and "MOUNTABLE" not in html
    assert _summary(r).splitlines()[-1].startswith(f"overall: FAIL — {said} (allowable σu/2 = 375 MPa)")

    # the verdict stage says it, the report only prints it
    from rigfem.cache import NO_CACHE
    from rigfem.job import Request, read_job
    from rigfem.verdict.part import Outcome, judge

    settings = read_job(Request("final-cm"), NO_CACHE).settings
    ok = [Outcome("plate_A", "plate", "original", 100.0, 1.0, 0.0)]
    assert judge(ok, settings).standing == "assembles; meets the rig rules; passes the stress criterion"
    assert judge(ok, settings, ("a rule",)).standing == said.removeprefix("the configuration ")
    assert judge(ok, settings, None).standing.startswith("assembles; the rig rules do not apply")  # a textbook one
    failing = [Outcome("plate_A", "plate", "original", 500.0, 1.0, 0.0)]
    assert judge(failing, settings).standing.endswith("fails the stress criterion")


def test_scene_descriptions_use_the_vocabulary(capsys):
    assert main(["check", "--list"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines() if line.strip()}
    assert "assembles; does not meet the rig rules" in lines["final-nc"]
    assert "assembles; meets the rig rules" in lines["final-cm"]


def test_the_sweep_and_the_explorer_use_the_vocabulary(tmp_path):
    """The sweep's counts and the explorer's words come from rigfem.rig.rules: a configuration on the
    rig is not said to mount; those that do not assemble are counted apart."""
    import json
    import re

    import pandas as pd

    from rigfem.rig.rules import ASSEMBLES, MEETS_RULES, STRESS
    from rigfem.sweep.configs import SweepParams
    from rigfem.sweep.explorer import write_explorer
    from rigfem.sweep.report import worst_markdown

    table = pd.DataFrame([dict(type="four-bar", b2=480.0, b3=840.0, b4=780.0, d=1020.0, rules_ok=True, status="ok",
                               note=None, mu_min_deg=38.7, mu_max_deg=135.6, peak_O2_N=472.0, peak_A_N=420.0,
                               peak_B_N=273.0, peak_O4_N=242.0, peak_torque_Nm=123.7, error_pct=10.0,
                               crank_rail_original_util_pct=38.7, limiting_part="crank_rail (original)",
                               max_util_pct=38.7, verdict="pass"),
                          dict(type="four-bar", b2=60.0, b3=60.0, b4=60.0, d=660.0, rules_ok=False,
                               status="cannot assemble", note=None, verdict=None)])
    md = worst_markdown(table, SweepParams())
    assert "configurations on the rig (each length on the 60 mm hole grid within its rail): 2" in md
    assert "do not assemble (cannot close over a full turn): 1" in md and "meet the rig rules (geometry/RIG.md §2): 1" in md
    assert "pass the stress criterion: 1" in md and "mountable" not in md.lower()
    page = write_explorer(tmp_path, {"four-bar": table}).read_text(encoding="utf-8")
    words = json.loads(re.search(r'<script type="application/json" id="words">(.*?)</script>', page).group(1))
    assert words == {"assembles": list(ASSEMBLES), "rules": list(MEETS_RULES), "stress": STRESS}
    assert "mount" not in page.lower()


def test_a_textbook_linkage_is_checked_without_the_rig_rules(tmp_path):
    """The compressor (a textbook linkage with a gas force) is no rig configuration: its check says
    the rig rules do not apply, not that it meets them."""
    from rigfem.cache import NO_CACHE
    from rigfem.job import Request, read_job
    from rigfem.pipeline import Output, run_check

    assert read_job(Request("final-cm"), NO_CACHE).rig_rules
    request = Request("mech5-compressor", {"fidelity": "draft", "parts": ["plate_A"], "modes": ["original"],
                                           "frames": 0})
    assert not read_job(request, NO_CACHE).rig_rules
    r = run_check(request, Output(tmp_path / "mech5", pictures=False))
    assert r["rules"] == [] and r["standing"].startswith("assembles; the rig rules do not apply; ")
