"""The sweep's pages for a teacher: a map's marker sits on the cell of its own configuration, the
lists have readable headers with units and name the broken rig rules (issue 40 §3).  Small tables
built here, and the committed results/sweep/ files (no sweep is run)."""

from pathlib import Path

import pandas as pd
import pytest

import rigfem.sweep.report as sweep_report
from rigfem.rig.rules import fourbar_rules
from rigfem.sweep.configs import SweepParams
from rigfem.sweep.report import FINAL_DESIGN, map_cells, summary_html, worst_markdown, write_maps

SWEEP = Path(__file__).resolve().parents[1] / "results" / "sweep"
FINAL = (480.0, 840.0, 780.0, 1020.0)
#: the final design passes; beside it, at the same b2, b3 and d, a longer rocker fails
ROWS = [(FINAL, 38.7, "pass"), ((480.0, 840.0, 840.0, 1020.0), 150.0, "fail"),
        ((480.0, 780.0, 780.0, 1020.0), 30.0, "pass"), ((480.0, 840.0, 780.0, 960.0), 45.0, "pass")]


def _table() -> pd.DataFrame:
    rows = []
    for (b2, b3, b4, d), util, verdict in ROWS:
        rules = fourbar_rules(b2, b3, b4, d)
        mu = [r.value for r in rules if r.unit == "deg"]
        rows.append(dict(type="four-bar", b2=b2, b3=b3, b4=b4, d=d, rules_ok=all(r.ok for r in rules), status="ok",
                         note=None, mu_min_deg=mu[0], mu_max_deg=mu[1], peak_O2_N=util * 10, peak_A_N=util * 9,
                         peak_B_N=util * 8, peak_O4_N=util * 7, peak_torque_Nm=util, crank_rail_original_util_pct=util,
                         post_B_original_util_pct=32.1, error_pct=10.0, limiting_part="crank_rail (original)",
                         max_util_pct=util, verdict=verdict))
    rows.append(dict(rows[0], b2=60.0, b3=60.0, b4=60.0, d=660.0, status="cannot assemble", rules_ok=False,
                     **{k: None for k in ("mu_min_deg", "crank_rail_original_util_pct", "max_util_pct", "verdict")}))
    return pd.DataFrame(rows)


def test_a_map_cell_is_one_configuration_and_the_star_sits_on_its_own():
    """The final design's cell shows the final design (38.7 %, pass), not the worst over the hidden length."""
    cells = map_cells(_table(), "d", "b3", {"b2": 480.0, "b4": 780.0})
    own = cells.loc[(840.0, 1020.0)]
    assert own["config_util_pct"] == 38.7 and own["verdict"] == "pass" and own["rules_ok"]
    assert cells.index.is_unique and len(cells) == 3  # the failing b4 = 840 mm is in another slice


def test_the_maps_are_slices_through_the_final_design(tmp_path, monkeypatch):
    seen = []
    real = sweep_report.map_cells

    def record(table, x, y, at):
        seen.append((x, y, at))
        return real(table, x, y, at)

    monkeypatch.setattr(sweep_report, "map_cells", record)
    assert write_maps(_table(), SweepParams(), tmp_path) == ["map_four-bar_d_b3.png", "map_four-bar_b4_b3.png"]
    hidden = {("d", "b3"): "b4", ("b4", "b3"): "d"}
    assert {(x, y) for x, y, _ in seen} == set(hidden)
    for x, y, at in seen:
        assert at[hidden[x, y]] == FINAL_DESIGN[hidden[x, y]] and set(at) == {"b2", hidden[x, y]}


def test_committed_map_star_cell_is_the_final_design_passing():
    table = pd.read_csv(SWEEP / "sweep_four-bar.csv.gz")
    for x, hidden in (("d", "b4"), ("b4", "d")):
        cell = map_cells(table, x, "b3", {"b2": 480.0, hidden: FINAL_DESIGN[hidden]}).loc[(840.0, FINAL_DESIGN[x])]
        assert cell["verdict"] == "pass" and cell["rules_ok"] and cell["config_util_pct"] == pytest.approx(38.7, abs=0.05)


def test_lists_have_readable_headers_and_name_the_broken_rules(tmp_path):
    md = worst_markdown(_table(), SweepParams())
    for raw in ("config_util_pct", "max_util_pct", "rules_ok", "mu_min_deg", "config_limiting", "max_reaction_N"):
        assert raw not in md, raw
    head = next(line for line in md.splitlines() if line.startswith("| b2 (mm)"))
    assert "μ min (deg)" in head and "its utilisation (% of σu/2)" in head and "rig rules broken" in head
    broken = next(line for line in md.splitlines() if line.startswith("| 480.0 | 840.0 | 780.0 | 960.0 |"))
    assert "transmission angle min: 34.22 deg, must be > 35 deg" in broken and "| pass |" in broken
    failing = next(line for line in md.splitlines() if line.startswith("| 480.0 | 840.0 | 840.0 | 1020.0 |"))
    assert "| none |" in failing and "| fail |" in failing
    page = summary_html(md, [], tmp_path, SweepParams())
    assert "rig rules broken" in page and "config_util_pct" not in page


def test_committed_pages_have_readable_headers_and_the_broken_rules():
    for kind in ("four-bar", "slider-crank"):
        for f in (f"worst_{kind}.md", f"sweep_{kind}.html"):
            text = (SWEEP / f).read_text(encoding="utf-8")
            assert "config_util_pct" not in text and "rules_ok" not in text and "rig rules broken" in text, f
