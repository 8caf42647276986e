"""Sweep of rig configurations: enumeration, rules, dynamics, superposed stresses, resume, Dask."""

from __future__ import annotations

import dataclasses
import json
import gzip

import numpy as np
import pandas as pd
import pytest

from rigfem.dynamics import peaks, simulate
from rigfem.linkage import four_bar
from rigfem.errors import InputError
from rigfem.fe import solve_cases
from rigfem.loads import part_cases
from rigfem.rig import fourbar_rules
from rigfem.cache import Cache
from rigfem.context import Context
from rigfem.sweep import SweepOptions, SweepParams, build_bases, case_peak, enumerate_configs, evaluate, run_sweep
from rigfem.sweep.bases import case_key
from rigfem.sweep.superpose import superposed_peaks

#: coarse meshes and three parts (a rail, a plate, the post) keep the default tests fast
CHECK = (("order", 1), ("size_mm", 14.0), ("local_size_mm", 7.0), ("bearing_directions", 4),
         ("parts", ("crank_rail", "plate_A", "post_B")))
FINAL = dict(b2=480.0, b3=840.0, b4=780.0, d=1020.0)
SMALL = dict(b2=120.0, b3=600.0, b4=540.0, d=660.0)
TOGGLE = dict(b2=540.0, b3=780.0, b4=660.0, d=660.0)
NO_LOOP = dict(b2=60.0, b3=60.0, b4=60.0, d=660.0)


@pytest.fixture(scope="module")
def params() -> SweepParams:
    return SweepParams(check=CHECK)


@pytest.fixture(scope="module")
def bases(params):
    return build_bases(params)


def test_enumeration_is_every_length_on_the_hole_grid():
    four = enumerate_configs(SweepParams())
    # crank 60..540 on the 700 mm rail, coupler/rocker 60..840 on 1000 mm, ground 660..2340 on 2500 mm
    assert len(four) == 9 * 14 * 14 * 29
    arr = np.array([[c["b2"], c["b3"], c["b4"], c["d"]] for c in four])
    assert np.all(arr % 60 == 0) and arr[:, 0].max() == 540 and arr[:, 1].max() == 840
    assert arr[:, 3].min() == 660 and arr[:, 3].max() == 2340
    slider = enumerate_configs(SweepParams(linkage_type="slider-crank"))
    assert len(slider) == 9 * 14 and all(c["offset"] == 0 for c in slider)


def test_rows_without_stress(params):
    row = evaluate(FINAL, params, None)
    pk = peaks(simulate(four_bar(**FINAL)))
    assert row["status"] == "ok" and row["peak_A_N"] == pytest.approx(pk["A"]["force_N"], rel=1e-12)
    assert row["peak_torque_Nm"] == pytest.approx(pk["torque"]["peak"], rel=1e-12)
    rules = fourbar_rules(**FINAL)
    assert sum(k.startswith("rule_") and k.endswith("_ok") for k in row) == len(rules) and row["rules_ok"]
    assert evaluate(NO_LOOP, params, None)["status"] == "cannot assemble"
    toggle = evaluate(TOGGLE, params, None)
    assert toggle["status"] == "toggle" and not any(k.startswith("peak_") for k in toggle)
    # b2 + d == b3 + b4: the loop closes on the grid but locks at a dead point; decided on the
    # lengths (within 1e-9 of their sum), so a float landing on either side cannot flip it
    for b4 in (660.0, 660.0 * (1 + 1e-12), 660.0 * (1 - 1e-12)):
        dead = evaluate(dict(b2=60.0, b3=60.0, b4=b4, d=660.0), params, None)
        assert dead["status"] == "toggle" and dead["note"].startswith("dead point: b2 + d = b3 + b4")


def test_bad_input():
    with pytest.raises(InputError, match="linkage type"):
        SweepParams(linkage_type="five-bar")
    with pytest.raises(InputError, match="speed_hz"):
        SweepParams(speed_hz=0.0)
    with pytest.raises(InputError, match="original"):
        SweepParams(linkage_type="slider-crank", model="original")


@pytest.mark.parametrize("cfg", [FINAL, SMALL])
def test_superposition_equals_full_solve(params, bases, cfg):
    """Sweep peaks == a full FE solve of the configuration's own cases on the same mesh.

    Cycle mode uses the basis directions themselves (1e-5: float32 fields); original mode splits
    the peak force direction over the two nearest of 72 basis directions (1e-3)."""
    s = params.settings()
    h = simulate(four_bar(**cfg))
    pk = peaks(h)
    ref = part_cases(h, pk, s)
    # same mesh as the sweep: refine every hole the basis refines
    refine = {k[:2]: c.refine for k, c in ((k, _spec_case(params, k)) for k in bases)}
    cases = [(m, dataclasses.replace(c, refine=refine[case_key(c)[:2]])) for m, c in ref]
    for (mode, case), res in zip(cases, solve_cases(cases, s)):
        b = bases[case_key(case)]
        peak, deg = case_peak(b, case)
        tol = 1e-5 if mode == "cycle" else 1e-3
        assert peak == pytest.approx(float(res.vm_rows.max()), rel=tol), (case.name, mode)
        assert deg == pytest.approx(float(case.rows[res.row]))
        assert peak == pytest.approx(case_peak(b, case, exact=True)[0], rel=1e-6)


def test_bounded_peak_is_exact_for_any_coefficients(bases):
    """The pruning by the von Mises triangle inequality never skips the peak: random load
    combinations (signs, sparsity, scales) on every basis, with the starting candidates (each
    field's top nodes) replaced by random nodes, so only the bound can find the peak."""
    rng = np.random.default_rng(7)
    for b in bases.values():
        k, n = b.S.shape[:2]
        blind = dataclasses.replace(b, top=rng.integers(0, n, size=b.top.shape))
        for trial in range(6):
            used = np.sort(rng.choice(k, size=min(k, rng.integers(1, 25)), replace=False))
            C = rng.standard_normal((rng.integers(1, 200), used.size)).astype(np.float32)
            C *= (rng.random(used.size) < 0.6) * 10.0 ** rng.uniform(-3, 1, used.size)
            if trial == 0:
                C = np.ones((50, used.size), np.float32)  # every field in step: the bound is tight
            ref = superposed_peaks(b, C, used, exact=True).max()
            assert superposed_peaks(b, C, used).max() == pytest.approx(ref, rel=1e-6)
            assert superposed_peaks(blind, C, used).max() == pytest.approx(ref, rel=1e-6)


def _spec_case(params, key):
    from rigfem.sweep.bases import _basis_specs

    specs = _basis_specs(params, params.settings())
    refine = sorted({g for k, (c, _) in specs.items() if k[:2] == key[:2] for g in c.refine})
    return dataclasses.replace(specs[key][0], refine=tuple(refine))


@pytest.mark.heavy  # over 10 s: the default run stays under 10 minutes
def test_against_run_check(params, bases, tmp_path):
    """End to end against rigfem.check.run_check: plates and posts on the same mesh agree to
    1e-4; rails within 10 % (run_check refines only the loaded holes, the sweep every hole)."""
    from rigfem.pipeline import Output, Request, run_check

    scene = tmp_path / "cfg.toml"
    scene.write_text("[linkage]\ntype = \"four-bar\"\n" + "".join(f"{k} = {v}\n" for k, v in FINAL.items())
                     + "speed_hz = 1.0\nmasses = \"rig\"\n")
    rep = run_check(Request(scene, {**dict(CHECK), "parts": list(dict(CHECK)["parts"]),
                                                             "frames": 0}), Output(tmp_path / "rc"))
    row = evaluate(FINAL, params, bases)
    for p in rep["parts"]:
        got = row[f"{p['name']}_{p['mode']}_util_pct"]
        tol = 0.10 if "rail" in p["name"] else 1e-4
        assert got == pytest.approx(p["utilisation_pct"], rel=tol), (p["name"], p["mode"])
        assert row[f"{p['name']}_{p['mode']}_deg"] == pytest.approx(p["crank_deg"], abs=1e-6)


CONFIGS = [NO_LOOP, FINAL, TOGGLE, SMALL, dict(b2=60.0, b3=840.0, b4=840.0, d=1500.0)]


def test_resume_gives_the_same_table(params, bases, tmp_path, monkeypatch):
    full = run_sweep(params, Context(Cache(tmp_path, 10**9)), SweepOptions(chunk_size=2, configs=tuple(CONFIGS), bases=bases))
    assert list(full["status"]) == ["cannot assemble", "ok", "toggle", "ok", "ok"]
    assert full.attrs["compute_seconds"] > 0
    num = full.select_dtypes("number")
    assert not np.isinf(num.to_numpy()).any() and num[full["status"] == "ok"].notna().all().all()
    chunk = {json.dumps(json.loads((f.parent / "manifest.json").read_text())["inputs"]["configs"]): f
             for f in tmp_path.glob("rigfem-entries/sweep_chunks/*/rows.csv")}
    text = "".join(c.read_text().lower() for c in chunk.values())
    assert "nan" not in text and "inf" not in text
    assert len(chunk) == 3
    second = chunk[json.dumps(CONFIGS[2:4])]
    second.write_text(second.read_text()[:40])  # a damaged (truncated) chunk is computed again
    import rigfem.sweep.run as sw

    calls = []
    real = sw.run_chunk
    monkeypatch.setattr(sw, "run_chunk", lambda c, p, b: calls.append(c) or real(c, p, b))  # the chunks it computes
    again = run_sweep(params, Context(Cache(tmp_path, 10**9)), SweepOptions(chunk_size=2, configs=tuple(CONFIGS), bases=bases))
    assert calls == [CONFIGS[2:4]]
    pd.testing.assert_frame_equal(full, again)


def test_dask_equals_serial(params, bases, tmp_path):
    from dask.distributed import LocalCluster

    serial = run_sweep(params, Context(Cache(tmp_path / "serial", 10**9)), SweepOptions(chunk_size=2, configs=tuple(CONFIGS), bases=bases))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp", host="127.0.0.1",
                      dashboard_address=None) as cluster:
        dist = run_sweep(params, Context(Cache(tmp_path / "dask", 10**9)), SweepOptions(chunk_size=2, scheduler=cluster.scheduler_address, configs=tuple(CONFIGS), bases=bases))
    pd.testing.assert_frame_equal(serial, dist)


def test_report_files(params, bases, tmp_path):
    from rigfem.sweep import write_report

    table = run_sweep(params, Context(Cache(tmp_path / "w", 10**9)), SweepOptions(chunk_size=5, configs=tuple(CONFIGS), bases=bases))
    files = write_report(table, params, tmp_path / "out")
    assert files == ["sweep_four-bar.csv.gz", "map_four-bar_d_b3.png", "map_four-bar_b4_b3.png", "worst_four-bar.md",
                     "sweep_four-bar.html", "explorer.html"]
    assert (tmp_path / "out" / "explorer.html").is_file()
    page = (tmp_path / "out" / "sweep_four-bar.html").read_text()
    assert page.count('src="data:image/png;base64,') == 2 and "computed (assemble, no toggle): 3" in page
    text = gzip.decompress((tmp_path / "out" / "sweep_four-bar.csv.gz").read_bytes()).decode().lower()
    assert "nan" not in text and "inf" not in text
    md = (tmp_path / "out" / "worst_four-bar.md").read_text()
    assert "worst configurations" in md and "2013 study" in md and "computed (assemble, no toggle): 3" in md


def test_cli_bad_input(capsys):
    from rigfem.cli import main

    assert main(["sweep", "--speed-hz", "0", "--quiet"]) == 2
    assert "speed_hz" in capsys.readouterr().err
    assert main(["sweep", "--scheduler", "localhost:8786", "--quiet"]) == 2
    assert "tcp://HOST:PORT" in capsys.readouterr().err


def test_cli_stores_chunks_in_the_cache(tmp_path, monkeypatch):
    """The CLI keeps finished chunks as cache entries, so a second run into another folder reads
    them; with an unusable cache they go to ``--out``/.work."""
    import rigfem.sweep.run
    from rigfem.cli import main
    from rigfem.errors import ComputeError

    seen = []

    def record(p, ctx, options):
        seen.append(ctx.cache.root)
        raise ComputeError("stop here")
    monkeypatch.setattr(rigfem.sweep.run, "run_sweep", record)
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))
    assert main(["sweep", "--four-bar", "--quiet", "--out", str(tmp_path / "a")]) == 3
    assert seen[-1] == tmp_path / "cache"
    (tmp_path / "file").write_text("not a folder")
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "file"))
    assert main(["sweep", "--four-bar", "--quiet", "--out", str(tmp_path / "b")]) == 3
    assert seen[-1] == tmp_path / "b" / ".work"


@pytest.mark.heavy
def test_default_local_cluster_equals_serial(params, bases, tmp_path):
    """The CLI's default path: a LocalCluster of worker processes inside this process."""
    serial = run_sweep(params, Context(Cache(tmp_path / "serial", 10**9)), SweepOptions(chunk_size=2, configs=tuple(CONFIGS), bases=bases))
    local = run_sweep(params, Context(Cache(tmp_path / "local", 10**9), workers=2), SweepOptions(chunk_size=2, configs=tuple(CONFIGS), bases=bases))
    pd.testing.assert_frame_equal(serial, local)


def test_stored_chunks_are_keyed_by_the_package(monkeypatch):
    """A sweep resumed after any change to the package (a part file, the mass catalogue, the code
    that computes a row) must not reuse chunks computed before it: its key holds the package hash
    (tests/test_cache.py edits a copy of the package)."""
    p = SweepParams()
    k0 = p.key()
    assert SweepParams().key() == k0
    monkeypatch.setattr("rigfem.cache.package_hash", lambda: "edited")
    assert p.key() != k0


@pytest.mark.heavy  # meshes and solves every part again in two child processes (~12 s)
def test_bases_built_in_child_processes_equal_the_ones_built_here(params, bases, tmp_path, monkeypatch):
    """Two geometries at a time in child processes, solved afresh (an empty cache: the children
    run the FE), give the same unit fields, in the same order, as one after another here."""
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))
    two = build_bases(params, workers=2)
    assert list(two) == list(bases)
    for key, b in bases.items():
        c = two[key]
        assert c.loads == b.loads and np.isclose(c.fe_mass, b.fe_mass, rtol=1e-12)
        assert np.allclose(c.S, b.S, rtol=1e-5, atol=1e-6 * np.abs(b.S).max())
        assert np.allclose(c.vm, b.vm, rtol=1e-5, atol=1e-6 * b.vm.max())


def test_bases_mapped_from_a_folder_equal_the_ones_held(params, bases, tmp_path):
    """With a folder (``rigfem synthesize --rig``), each basis's fields are written there as they
    are made and memory-mapped, not held: the same numbers as the bases held in memory; a mapped
    field pickles as its file name (a child process maps the same file)."""
    import pickle

    mapped = build_bases(params, folder=tmp_path)
    assert list(mapped) == list(bases)
    for key, b in bases.items():
        m = mapped[key]
        assert isinstance(m.S, np.memmap) and isinstance(m.vm, np.memmap)
        assert np.array_equal(m.S, b.S) and np.array_equal(m.vm, b.vm) and np.array_equal(m.top, b.top)
        assert len(pickle.dumps(m.S)) < 1000 and np.array_equal(pickle.loads(pickle.dumps(m.S)), b.S)


def test_the_first_error_of_a_bases_child_ends_the_other_at_once(params, monkeypatch, tmp_path):
    """The second child's error is raised at once, without waiting for the first (the largest
    part), which sees its cancel event (a real child is ended within a poll)."""
    import threading
    import time

    from rigfem.mesh import mesher, worker

    lock, meshed, seen = threading.Lock(), [], []

    def fake_mesh(part, settings, cache=None):  # the first part's mesh at once, the others a little later
        with lock:
            meshed.append(part)
            first = len(meshed) == 1
        if not first:
            time.sleep(0.5)
        return first

    def fake_call(fn, first, specs, *args, cancel: threading.Event, what: str):
        if first:  # the largest part runs until it is cancelled
            if not cancel.wait(60):
                raise AssertionError("never cancelled")
            seen.append("cancelled")
            raise worker.ComputeError("unit bases cancelled")
        raise InputError("a part that cannot be solved")

    monkeypatch.setattr(mesher, "mesh_part", fake_mesh)
    monkeypatch.setattr(worker, "call", fake_call)
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path))  # no basis stored: the children must build them
    t0 = time.perf_counter()
    with pytest.raises(InputError, match="cannot be solved"):
        build_bases(params, workers=2)
    assert time.perf_counter() - t0 < 30 and seen == ["cancelled"]
