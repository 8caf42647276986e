"""Issue 24 §1 and §7: the sweep grid and the rig synthesis search are estimated from their
counts before any work and refused (exit 2, the estimate, the limit and the override) past the
machine's memory or the time limit; long commands name their stages when not on a terminal."""

from __future__ import annotations

import re
import time

import pytest

import rigfem.cli.progress as progress
from rigfem.cli import main
from rigfem.settings import ALLOW_LARGE_ENV, MAX_JOB_HOURS
from rigfem.sweep.cost import JobCost, check_cost, sweep_cost, turning
from rigfem.sweep.configs import SweepParams, enumerate_configs
from said import one_line

FUNCTION = ["synthesize", "function", "x*log(x)", "--x", "1", "3", "--input", "20", "90", "--output", "80", "90",
            "--ground", "2", "--rig"]
FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"]


def test_turning_configurations_are_the_ones_the_sweep_checks():
    # the committed sweep computed these many (results/sweep/worst_*.md: "computed (assemble, no toggle): 3306" / "81")
    p = SweepParams()
    assert turning(p, enumerate_configs(p)) == 3306
    q = SweepParams(linkage_type="slider-crank")
    assert turning(q, enumerate_configs(q)) == 81


def test_sweep_cost_grows_with_samples_and_workers():
    p, big = SweepParams(), SweepParams(samples=36000)
    c = enumerate_configs(p)
    base, slow, wide = sweep_cost(p, c, 2), sweep_cost(big, c, 2), sweep_cost(big, c, 200)
    assert base.seconds < MAX_JOB_HOURS * 3600 and slow.seconds > 50 * base.seconds
    assert wide.gib > 100 * base.gib > 0


@pytest.mark.parametrize("argv,needle", [
    (["--samples", "100000"], re.compile(r"× 100000 crank angles on \d+ workers?: estimated [\d.]+ h, more than "
                                         r"the limit of 24 h; reduce the job, or pass rigfem --allow-large")),
    (["--samples", "36000", "--workers", "256"], re.compile(r"estimated [\d.]+ GiB of memory, more than the "
                                                            r"machine's [\d.]+ GiB")),
])
def test_sweep_past_the_limits_is_refused_in_seconds_before_any_file(tmp_path, capsys, argv, needle):
    t0 = time.monotonic()
    assert main(["sweep", *argv, "--quiet", "--out", str(tmp_path / "sw")]) == 2
    err = capsys.readouterr().err
    assert needle.search(one_line(err)) and time.monotonic() - t0 < 30
    assert not (tmp_path / "sw").exists()


def test_allow_large_lifts_the_limits(monkeypatch):
    huge = JobCost("a job", 1e6, 1e9)
    with pytest.raises(Exception, match="1e\\+06 GiB of memory.*and 2.78e\\+05 h"):
        check_cost(huge, 16.0)
    monkeypatch.setenv(ALLOW_LARGE_ENV, "1")
    check_cost(huge, 16.0)


def test_synthesis_search_past_the_memory_is_refused_before_it_starts(monkeypatch, capsys):
    import rigfem.mesh.mesher as mesher

    monkeypatch.setattr(mesher, "MACHINE_GIB", 0.05)
    assert main([*FUNCTION, "--fidelity", "standard"]) == 2
    err = capsys.readouterr().err
    assert "stress verdicts of 5 rig four-bars (unit solutions of 6 parts at standard): estimated" in err
    assert "rigfem --allow-large" in one_line(err)


def test_synthesize_rig_names_its_stages(monkeypatch, capsys):
    monkeypatch.setattr(progress, "AFTER_S", 0.0)
    assert main([*FUNCTION, "--no-stress"]) == 0
    err = capsys.readouterr().err
    assert re.search(r"^rigfem synthesize function: ranking the rig four-bars … \d+ s$", err, re.M)


def test_check_names_its_stages(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(progress, "AFTER_S", 0.0)
    argv = [a for a in FAST if a != "--quiet"]   # --quiet silences the stage lines (test_cli_unix)
    assert main(["check", "final-cm", "--out", str(tmp_path / "o"), *argv]) == 0
    stages = re.findall(r"^rigfem check: (.+?)(?: · .*)? … \d+ s$", capsys.readouterr().err, re.M)
    assert [s for i, s in enumerate(stages) if s not in stages[:i] and s != "running"] == [
        "dynamics", "solving part plate_A (coarse)", "report", "report: reactions and peaks pictures, field files",
        "report: the parts' pictures", "report: report.json, report.md, report.html"]  # the ladder's first level
