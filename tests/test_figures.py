"""The figures of README and the docs, and the results/benchmarks tables, agree with the dated records."""

from __future__ import annotations

import argparse
import copy
import datetime
import importlib
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmark scripts import each other as siblings
# the repository's own scripts (not a package), loaded as the modules their siblings import
publish, record, tables = (importlib.import_module(m) for m in ("publish", "record", "tables"))


@pytest.fixture(scope="module")
def recs() -> dict:
    return publish.load()


def test_readme_and_tables_agree_with_the_records():
    assert publish.main(["--check"]) == 0


def test_every_record_is_complete(recs):
    assert publish.problems(recs) == []
    assert "kinematics" in recs and "le10" in recs
    for name in set(tables.RENDER) & set(recs):
        r = recs[name]
        datetime.datetime.fromisoformat(r["date"])
        assert len(r["commit"]["sha"]) == 40 and r["command"].startswith("python benchmarks/")


@pytest.mark.parametrize("key", ["date", "commit", "machine", "command", "samples"])
def test_a_record_lacking_a_key_is_refused(recs, key):
    bad = copy.deepcopy(recs)
    del bad["le10"][key]
    assert any(f"le10.json: no {key!r}" in p for p in publish.problems(bad))


def test_a_summary_edited_by_hand_is_refused(recs):
    bad = copy.deepcopy(recs)
    bad["le10"]["summary"]["100 mm rigfem"]["wall_s"]["median"] *= 0.5
    assert any("summary differs from its raw samples" in p for p in publish.problems(bad))
    bad["le10"]["samples"]["100 mm rigfem"] = []
    assert any("no raw samples" in p for p in publish.problems(bad))


PERF_PAGE = ROOT / "docs" / "performance.md"  #: the page that holds the figures tables


def test_a_figure_that_differs_from_its_record_is_caught(recs):
    text = PERF_PAGE.read_text()
    assert publish.render_page(text, recs) == text
    moved = copy.deepcopy(recs)
    for s in moved["kinematics"]["samples"].values():
        for x in s:
            x["ms"] *= 2.0
    moved["kinematics"]["summary"] = record.summarise(moved["kinematics"]["samples"])
    moved["kinematics"]["derived"]["total ms"] *= 2.0
    assert publish.render_page(text, moved) != text
    typed = text.replace(f"**{recs['kinematics']['derived']['total ms']:.1f} ms**", "**99.0 ms**", 1)
    assert typed != text and publish.render_page(typed, recs) == text


def test_a_figure_row_naming_a_missing_result_file_is_caught():
    text = PERF_PAGE.read_text()
    assert publish.named_paths(text) == []
    bad = text.replace("<!-- perf-figures:end -->", "| x | y | results/benchmarks/nowhere.md |\n<!-- perf-figures:end -->")
    assert publish.named_paths(bad) == ["results/benchmarks/nowhere.md"]


def test_one_figure_per_quantity(recs):
    """A block or span on two pages, or on none, is refused; where two records measure the same work the
    performance table's figure is the one shown (the sweep's older 2-worker times are not quoted)."""
    texts = {p: p.read_text() for p in publish.pages()}
    assert publish.placement(texts, recs) == []
    sweep = PERF_PAGE.parent / "guide" / "sweep.md"
    twice = {**texts, ROOT / "README.md": texts[ROOT / "README.md"] + "\n<!-- fig:sweep-2 -->x<!-- /fig -->\n"}
    assert any("fig:sweep-2 is on 2 pages" in p for p in publish.placement(twice, recs))
    none = {**texts, sweep: texts[sweep].replace("<!-- fig:sweep-2 -->", "").replace("<!-- /fig -->.", ".", 1)}
    assert any("fig:sweep-2 is on no page" in p for p in publish.placement(none, recs))
    rendered = publish.render_page(texts[PERF_PAGE], recs)
    old = publish.hms(publish.med(recs["sweep"], "cold, 2 workers"))
    assert old not in rendered.split("<!-- perf-figures:begin -->")[1], "the sweep row quotes the older figure"


def test_every_benchmark_writes_through_the_record_module():
    for f in sorted((ROOT / "benchmarks").glob("*.py")):
        src = f.read_text()
        if "results/benchmarks" in src and f.name not in ("record.py", "publish.py", "tables.py"):
            assert "write_record(" in src, f"{f.name} writes results/benchmarks without benchmarks/record.py"
            assert '"results" / "benchmarks"' not in src, f"{f.name} writes its own files in results/benchmarks"


def test_le10_target_is_the_studys():
    from rigfem.verification.le10 import TARGET_SYY

    assert tables.LE10_TARGET == TARGET_SYY


def test_peak_memory_is_the_whole_process_tree(tmp_path):
    child = "import time; b = bytearray(300 * 2**20); time.sleep(1.5)"
    parent = f"import subprocess, sys; subprocess.run([sys.executable, '-c', {child!r}])"
    r = record.timed_process([sys.executable, "-c", parent])
    assert r["exit"] == 0 and r["peak_tree_rss_mib"] > 300 and r["wall_s"] > 1.5


def test_wall_time_ends_with_the_process_not_at_the_next_poll():
    """A 0.1 s process polled every 5 s: its wall time is its own, not the poll interval (the old
    loop slept a whole interval before it saw the exit)."""
    r = record.timed_process([sys.executable, "-c", "import time; time.sleep(0.1)"], poll_s=5.0)
    assert r["exit"] == 0 and 0.1 <= r["wall_s"] < 2.5


def test_write_record_computes_the_summaries(tmp_path):
    path = record.write_record("demo", {"a": [{"wall_s": 3.0}, {"wall_s": 1.0}, {"wall_s": 2.0}]}, {"x": 1},
                               command="python benchmarks/demo.py", out=tmp_path)
    r = json.loads(path.read_text())
    assert all(k in r for k in record.REQUIRED)
    assert r["summary"]["a"]["wall_s"] == {"median": 2.0, "min": 1.0, "max": 3.0, "n": 3}
    assert r["machine"]["cores"] >= 1 and r["machine"]["memory_gib"] > 0


def _fake_perf(tmp_path: Path, samples: dict) -> dict:
    """A tiny perf record written by the real path (record.write_record, bench_perf's derive and merge)."""
    bench_perf = importlib.import_module("bench_perf")
    base = {"commit": "ab" * 20, "dirty": False, "baseline": "v0"} if any("before: " in k for k in samples) else None
    merged, prov = bench_perf.merge(samples, None, base)
    path = record.write_record("perf", merged, bench_perf.derive(merged), {"provenance": prov, "baseline": base},
                               command="fake", out=tmp_path)
    return json.loads(path.read_text())


def _run(wall: float, rss: float = 50.0, **extra) -> dict:
    return {"wall_s": wall, "peak_tree_rss_mib": rss, "exit": 0, "load_before": [1.0, 1.0, 1.0], **extra}


def test_perf_table_says_met_from_the_data(tmp_path):
    """Each row is met / not met / not measured from the record and bench_perf.GOALS, never typed."""
    rec = _fake_perf(tmp_path, {"help cold": [_run(0.1), _run(0.2)], "help warm": [_run(0.1)],
                                "parts cold": [_run(0.5)], "parts warm": [_run(0.1)],
                                "check draft cold": [_run(9.0, 2000.0)], "check draft warm": [_run(2.5, 1200.0)],
                                "check standard cold": [_run(14.0, 900.0, folder_mb=16.0)],
                                "dof": [_run(1.0, 100.0 + 0.5 * n / 1000, dof=n) for n in (10_000, 100_000, 1_000_000)],
                                "ccx": [_run(5.0, ratio=0.52, dof=167_529)]})
    assert publish.problems({"perf": rec}) == []
    rows = {ln.split(" | ")[0].lstrip("| "): ln for ln in tables.perf_rows(rec)[2:]}
    assert rows["`rigfem --help`"].endswith("| met |") and "0.15 s" in rows["`rigfem --help`"]
    assert rows["`rigfem parts`"].endswith("| **not met** |")  # cold 0.5 s > 0.3 s although warm is fast
    assert rows["`rigfem check final-cm --force --fidelity draft`"].endswith("| met |")  # the draft goal is cold only
    assert rows["`rigfem check final-cm --force`, standard"].endswith("| not measured |")  # no warm series
    folder = rows["result folder of a standard check (final-cm)"]
    assert "folder 16.0 MB" in folder and folder.endswith("| **not met** |")  # the standard cold run's folder
    assert "ratio 0.52" in rows[next(k for k in rows if "CalculiX" in k)] and "**not met**" in rows[
        next(k for k in rows if "CalculiX" in k)]
    dof = rows[next(k for k in rows if k.startswith("peak RSS"))]
    assert "up to 1,000,000 DOF, 0.5 MiB per 1000 DOF, R² 1.000" in dof and dof.endswith("| met |")
    block = publish.blocks({**publish.load(), "perf": rec})["performance"]
    assert "| `rigfem --help` | < 0.3 s (issue 26) | 0.15 s | 0.10 s | 50 MiB | met |" in block and "perf.md" in block


def test_perf_table_shows_a_baseline_before_and_after(tmp_path):
    """A record with a baseline's series reads "before → after" per figure; met is the after's alone."""
    rec = _fake_perf(tmp_path, {"before: check standard cold": [_run(30.0, 1500.0, folder_mb=145.0)],
                                "before: check standard warm": [_run(2.0)],
                                "check standard cold": [_run(14.0, 900.0, folder_mb=12.0)],
                                "check standard warm": [_run(0.8)], "calibration": [{"seconds": 2.0}]})
    rows = {ln.split(" | ")[0].lstrip("| "): ln for ln in tables.perf_rows(rec)[2:]}
    std = rows["`rigfem check final-cm --force`, standard"]
    assert "| 30.0 s → 14.0 s | 2.00 s → 0.80 s | 1500 MiB → 900 MiB |" in std and std.endswith("| met |")
    assert "145.0 MB → 12.0 MB" in rows["result folder of a standard check (final-cm)"]
    assert rec["derived"]["check standard cold after / before"] == pytest.approx(14 / 30)
    assert rec["derived"]["check standard cold / calibration"] == pytest.approx(7.0)
    assert "before → after: the code of v0" in tables.perf_note(rec) and "calibration" in tables.perf(rec)



def test_perf_table_profiles_the_folder_and_the_calculix_row(tmp_path):
    """The folder row's bytes by kind and the CalculiX row's FE steps come from the same runs as the rows."""
    kinds = {"vtu_critical": 20.0, "vtu_frames": 25.0, "png": 5.0, "html": 2.0, "json": 0.05, "md": 0.02,
             "pvd": 0.0, "other": 0.0}
    steps = {"assembly": 1.5, "supports_loads": 2.0, "factorise": 5.0, "solve": 0.5, "stress": 0.3, "fe_total": 9.3}
    rec = _fake_perf(tmp_path, {"check standard cold": [_run(60.0, 900.0, folder_mb=52.07, folder_kinds_mb=kinds)],
                                "ccx": [_run(50.0, ratio=0.44, dof=167_553, rigfem_steps_s=steps, ccx_s=21.1)]})
    folder, ccx = tables.profiles(rec)
    assert folder == ("The result folder by kind: after: VTU at the critical angles 20.0 MB, VTU "
                      "animation frames 25.0 MB, PNG 5.0 MB, HTML 2.0 MB, JSON 0.1 MB of 52.1 MB.")
    assert "factorisation 5.00 s, solve 0.50 s, stress recovery 0.30 s of rigfem's 9.30 s; CalculiX 21.10 s" in ccx
    assert folder in tables.perf(rec) and ccx in tables.perf(rec)

def test_every_cold_run_has_fresh_caches_of_its_own(monkeypatch):
    """A cold series never reuses a cache an earlier run of it filled (a second run would be warm);
    the warm runs share the one their first run filled."""
    bench_perf = importlib.import_module("bench_perf")
    seen = []
    monkeypatch.setattr(bench_perf, "_rigfem", lambda args, env, ok=(0,): seen.append(env["RIGFEM_CACHE"]) or _run(1.0))
    assert len(bench_perf.row_synth(argparse.Namespace(repeats=3), Path("."))["synthesize --rig cold"]) == 3
    assert len(set(seen)) == 3
    seen.clear()
    cold, warm = bench_perf.cold_warm(lambda env, tmp: bench_perf._rigfem([], env), Path("."), 2)
    assert len(set(seen[:2])) == 2 and seen[2:] == [seen[1]] * 2  # warm: the last cold run's caches


def test_perf_record_keeps_rows_not_remeasured(tmp_path):
    bench_perf = importlib.import_module("bench_perf")
    old = _fake_perf(tmp_path, {"help cold": [_run(0.1)], "parts cold": [_run(0.5)]})
    merged, prov = bench_perf.merge({"parts cold": [_run(0.2)]}, old, None)
    assert merged["help cold"] == old["samples"]["help cold"] and merged["parts cold"][0]["wall_s"] == 0.2
    assert set(prov) == {"help cold", "parts cold"}


def test_the_timeline_groups_each_commands_stages_from_the_record(tmp_path):
    """profile_timeline's record renders per command: its wall time, and each stage group's seconds and
    share (the per-part FE stages as one group), in the order they first ran."""
    stages = [{"stage": "imports (rigfem.cli)", "start_s": 0.0, "seconds": 1.0, "peak_tree_rss_mib": 100.0},
              {"stage": "solving part plate_A (coarse)", "start_s": 1.0, "seconds": 4.0, "peak_tree_rss_mib": 800.0},
              {"stage": "solving part post_B (draft) · 4 of 12 cases done", "start_s": 5.0, "seconds": 5.0,
               "peak_tree_rss_mib": 900.0},
              {"stage": "report: the parts' pictures", "start_s": 10.0, "seconds": 10.0, "peak_tree_rss_mib": 1500.0}]
    path = record.write_record("timeline", {"check cold": [_run(20.0, 1500.0, stages=stages)]}, {}, command="fake",
                               out=tmp_path)
    rec = json.loads(path.read_text())
    row = tables.timeline_rows(rec)[2]
    assert row.startswith("| check cold | 20.0 s | 1500 MiB |")
    assert ("before the first stage: imports, arguments, the command's first work 1.0 s (5 %, 100 MiB); "
            "FE: mesh, solve and refine each part 9.0 s (45 %, 900 MiB); "
            "report: the parts' pictures 10.0 s (50 %, 1500 MiB)") in row
    assert "cold standard check 20 s: FE 9 s, the report after the verdict 10 s" in publish._timeline(rec)
    assert "| solving part post_B (draft) · 4 of 12 cases done | 5.0 s | 5.00 | 25 % | 900 MiB |" in tables.timeline(rec)


def test_same_results_compares_peaks_verdicts_and_meshes():
    """benchmarks/bench_same_results.py: a peak moved by 1e-6 is measured as 1e-6, a changed verdict or
    mesh and a missing part case are named; identical reports differ by 0."""
    compare = importlib.import_module("bench_same_results").compare

    part = {"name": "crank_rail", "mode": "cycle", "peak_mpa": 100.0, "error_pct": 5.0, "utilisation_pct": 26.7,
            "max_displacement_mm": 0.1, "crank_deg": 30.0, "verdict": "pass",
            "mesh": {"level": "coarse", "fe_nodes": 1000, "tets": 400}}
    old = {"parts": [part, {**part, "name": "plate_A", "mesh": dict(part["mesh"])}]}
    assert compare(old, old)["rel"]["peak_mpa"] == 0.0 and not compare(old, old)["different"]
    moved = copy.deepcopy(old)
    moved["parts"][1]["peak_mpa"] *= 1 + 1e-6
    moved["parts"][0]["verdict"] = "fail"
    moved["parts"][0]["mesh"]["fe_nodes"] = 1001
    c = compare(old, moved)
    assert c["rel"]["peak_mpa"] == pytest.approx(1e-6, rel=1e-5) and c["worst_peak_case"] == "plate_A cycle"
    assert c["different"] == ["crank_rail cycle: verdict pass -> fail", "crank_rail cycle: mesh.fe_nodes 1000 -> 1001"]
    assert compare(old, {"parts": old["parts"][:1]})["missing"] == ["plate_A cycle"]
    assert compare(old, old)["bit for bit"] == ["crank_rail cycle", "plate_A cycle"]
    assert c["bit for bit"] == ["crank_rail cycle"]  # its verdict and mesh changed, not its figures


def test_a_records_own_output_does_not_make_the_tree_dirty(tmp_path, monkeypatch):
    """bench_perf.py writes its record after every row: results/ changing is not a modified tree,
    a tracked code file changing is."""
    import subprocess

    record = importlib.import_module("record")
    (tmp_path / "results").mkdir()
    for f in ("code.py", "results/perf.json"):
        (tmp_path / f).write_text("0\n")
    for args in (["init", "-q"], ["add", "."], ["-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "x"]):
        subprocess.run(["git", "-C", str(tmp_path), *args], check=True)
    monkeypatch.setattr(record, "ROOT", tmp_path)
    (tmp_path / "results/perf.json").write_text("1\n")
    assert record.commit()["dirty"] is False
    (tmp_path / "code.py").write_text("1\n")
    assert record.commit()["dirty"] is True
