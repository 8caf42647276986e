"""Sweep every mountable rig configuration: rules, dynamics and part stresses by superposition.

For each rail geometry and support set, one FE factorisation gives the *unit* stress fields
of every load a configuration can apply (bearing loads in fixed directions on every hole a
coupling can use, the rail's inertia fields; plate bore and post screws).  A configuration's
stress at any crank angle is then ``σ = Σ_k c_k σ_k`` with the coefficients that
:func:`rigfem.loads.cases.part_cases` produces for it, so the sweep does no FE solve per
configuration.  The peak von Mises is exact but evaluated only where it can be: nodes whose
stress bound (the triangle inequality of the von Mises norm over the unit fields) reaches a
lower bound of the peak (:func:`case_peak`); the tests check it against every node and
against a full :func:`rigfem.check.run_check`.

Chunks of configurations run serially or on Dask (an in-process LocalCluster by default, or
an existing scheduler); finished chunks are stored as CSV in a work folder keyed by the
sweep parameters, so an interrupted sweep resumes where it stopped.

Bearing directions not in the basis (the study's case along the peak force direction) are
split over the two neighbouring basis directions (:data:`ORIGINAL_DIRECTIONS` of them), as
the cycle mode does with its ``bearing_directions``.

Units: mm, N, MPa, deg.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import socket
import tempfile
import time
from pathlib import Path

import numpy as np

from rigfem.dynamics.cycle import simulate
from rigfem.dynamics.history import peaks
from rigfem.errors import ComputeError, InputError, check_range
from rigfem.files import whole_file
from rigfem.linkage.mechanisms import four_bar, slider_crank
from rigfem.loads.cases import part_cases
from rigfem.settings import PRESET_ERROR_PCT, CheckSettings
from rigfem.verdict.criterion import half_ultimate, overall
from rigfem.mesh.mesher import MACHINE_GIB
from rigfem.sweep.cost import check_cost, sweep_cost
from rigfem.sweep.bases import UnitBasis, build_bases, case_key, case_peak, mapped
from rigfem.sweep.configs import JOINTS, LENGTHS, SweepParams, enumerate_configs, rules_row


# ----------------------------------------------------------------------------- one configuration
def _dead_point(linkage_type: str, cfg: dict, rtol: float = 1e-9) -> str:
    """Why a loop that closes locks on the way round (a change-point linkage), or ''.

    A four-bar with b2 + d = b3 + b4 (or |d - b2| = |b3 - b4|) and a slider-crank with
    b2 + |offset| = b3 pass through a position where two links align; whether a sampled solve stops
    there is a float knife edge, so it is decided here on the lengths.
    """
    if linkage_type == "four-bar":
        b2, b3, b4, d = (cfg[k] for k in ("b2", "b3", "b4", "d"))
        tol = rtol * (b2 + b3 + b4 + d)
        if abs(b2 + d - b3 - b4) <= tol:
            return f"b2 + d = b3 + b4 = {b3 + b4:g} mm (coupler and rocker align)"
        if abs(abs(d - b2) - abs(b3 - b4)) <= tol:
            return f"|d - b2| = |b3 - b4| = {abs(b3 - b4):g} mm (coupler and rocker fold)"
    elif linkage_type == "slider-crank":
        b2, b3, e = cfg["b2"], cfg["b3"], abs(cfg.get("offset", 0.0))
        if abs(b2 + e - b3) <= rtol * (b2 + b3 + e):
            return f"b2 + |offset| = b3 = {b3:g} mm (rod and crank align)"
    return ""


def evaluate(cfg: dict, p: SweepParams, bases: dict[tuple, UnitBasis] | None,
             settings: CheckSettings | None = None) -> dict:
    """One table row: lengths, every rule, peak reactions and per-part utilisation and verdict.

    ``bases=None`` skips the stress check (rules and dynamics only).  A configuration that
    cannot be assembled or passes through a toggle gets a status and no numbers.
    """
    from rigfem.linkage.model import AssemblyError, ClosureError

    s = settings or p.settings()
    row: dict = {"type": p.linkage_type, **cfg, **rules_row(p, cfg)}
    with np.errstate(divide="ignore", invalid="ignore"):  # toggles are flagged below, never numbers
        dead = _dead_point(p.linkage_type, cfg)
        if dead:  # decided on the lengths, not on whether the solver's floats reach the lock
            return {**row, "status": "toggle", "note": f"dead point: {dead}"}
        try:
            lk = (four_bar(**cfg, rails_mm=p.rails) if p.linkage_type == "four-bar"
                  else slider_crank(**cfg, rails_mm=p.rails))
        except ClosureError:
            return {**row, "status": "cannot assemble"}
        try:
            h = simulate(lk, samples=p.samples, speed_hz=p.speed_hz, model=p.model)
        except AssemblyError as exc:  # the loop just closes: it locks at a dead point on the way
            return {**row, "status": "toggle", "note": f"dead point: {exc}"}
    if h.meta.get("mu_deg"):
        row["mu_min_deg"], row["mu_max_deg"] = h.meta["mu_deg"]["min"], h.meta["mu_deg"]["max"]
    if h.meta.get("singular"):
        return {**row, "status": "toggle"}
    pk = peaks(h)
    if any(v.get("singular") for v in pk.values()):
        return {**row, "status": "toggle"}
    for j in JOINTS[p.linkage_type]:
        row[f"peak_{j}_N"] = pk[j]["force_N"]
        row[f"peak_{j}_deg"] = pk[j]["crank_deg"]
    row["peak_torque_Nm"] = pk["torque"]["peak"]
    row["status"] = "ok"
    if bases is None:
        return row
    err = PRESET_ERROR_PCT.get(p.fidelity, 0.0)  # the preset's accuracy target as the error band
    worst, verdicts = ("", 0.0), []
    for mode, case in part_cases(h, pk, s):
        peak, deg = case_peak(bases[case_key(case)], case)
        v = half_ultimate(peak, s.material.sigma_u, err, s.limit_factor, loaded=bool(np.any(case.coef)))
        row[f"{case.name}_{mode}_mpa"] = peak
        row[f"{case.name}_{mode}_deg"] = deg
        row[f"{case.name}_{mode}_util_pct"] = v.utilisation_pct
        verdicts.append({"verdict": v.verdict})
        if v.utilisation_pct > worst[1]:
            worst = (f"{case.name} ({mode})", v.utilisation_pct)
    row["limiting_part"], row["max_util_pct"] = worst
    row["error_pct"] = err
    row["verdict"] = overall(verdicts)  # the check's verdict: pass, fail or undecided
    return row


# ----------------------------------------------------------------------------- chunks, resume, Dask
def run_chunk(configs: list[dict], p: SweepParams, bases: dict[tuple, UnitBasis] | None) -> list[dict]:
    """Table rows of a chunk of configurations (what a Dask task runs)."""
    s = p.settings()
    rows = [evaluate(c, p, bases, s) for c in configs]
    for r in rows:
        bad = [k for k, v in r.items() if isinstance(v, float) and not np.isfinite(v)]
        if bad:
            raise InputError(f"configuration {configs[0]}: non-finite {', '.join(bad)}")
    return rows


def _column_order(cols: list[str], p: SweepParams) -> list[str]:
    lead = ["type", *LENGTHS[p.linkage_type]]
    rules = [c for c in cols if c.startswith("rule")]
    tail = ["limiting_part", "max_util_pct", "verdict"]
    rest = [c for c in cols if c not in lead + rules + tail]
    return [c for c in lead + rules + rest + tail if c in cols]


def _chunk(work: Path, key: str, i: int, configs: list[dict]) -> tuple[Path, dict]:
    """Folder and inputs of stored chunk ``i`` of the sweep ``key``: a verified cache entry
    (rigfem.mesh.cache), so a damaged chunk is computed again, never read."""
    return work / f"chunk_{i:05d}", {"sweep": key, "configs": configs}


def _write_chunk(work: Path, key: str, i: int, configs: list[dict], rows: list[dict]) -> None:
    import pandas as pd

    from rigfem.mesh.cache import read_entry, write_entry

    folder, inputs = _chunk(work, key, i, configs)
    text = pd.DataFrame(rows).to_csv(index=False, float_format="%.10g")
    if not (write_entry(folder, inputs, lambda d: (d / "rows.csv").write_text(text)) or read_entry(folder, inputs)):
        raise ComputeError(f"could not store sweep chunk {i} in {work} (disk full or not writable?)")


def run_sweep(p: SweepParams, work_dir, *, chunk_size: int = 64, workers: int = 1,
              scheduler: str | None = None, distributed: bool | None = None, configs: list[dict] | None = None,
              progress: bool = True, bases: dict | None = None, solver: str = "auto", on_stage=None,
              machine_gib: float = MACHINE_GIB):
    """Run (or resume) a sweep; return the table (pandas DataFrame, one row per configuration).

    ``work_dir``: where finished chunks are stored (a folder per parameter hash is made in it).
    ``distributed``: run chunks on Dask (default: when ``workers > 1`` or a ``scheduler`` is
    given); ``scheduler`` is ``tcp://HOST:PORT`` of an existing cluster, else a LocalCluster
    with ``workers`` processes runs inside this process; with ``workers`` > 1 the unit bases
    are built two geometries at a time (:func:`~rigfem.sweep.bases.build_bases`).
    ``configs``: only these configurations (default: every mountable one).  ``bases``: unit
    solutions already built for ``p``.
    The job's cost is estimated from the counts before any work (:mod:`rigfem.sweep.cost`;
    past ``machine_gib`` or the time limit: InputError).  ``on_stage(text)`` hears each stage.
    """

    import pandas as pd
    from tqdm import tqdm

    from rigfem.mesh.cache import read_entry

    t0 = time.perf_counter()
    check_range("chunk_size", chunk_size, 1, 100_000)
    check_range("workers", workers, 1, 256)
    configs = enumerate_configs(p) if configs is None else configs
    cost = sweep_cost(p, configs, workers, bases=bases is None)
    check_cost(cost, machine_gib)  # from the counts, before anything is built
    if scheduler is not None and distributed is not False:
        reach_scheduler(scheduler)  # in seconds, before the unit solutions are built
    tag = hashlib.sha256(json.dumps([configs, chunk_size], sort_keys=True).encode()).hexdigest()[:8]
    key = p.key()
    work = Path(work_dir) / f"{key}-{tag}"
    work.mkdir(parents=True, exist_ok=True)
    for path, text in ((Path(work_dir) / ".gitignore", "*\n"),  # stored chunks never enter the repository
                       (work / "params.json", json.dumps(dataclasses.asdict(p), indent=1, default=str))):
        with whole_file(path) as tmp:
            tmp.write_text(text)
    chunks = [configs[i:i + chunk_size] for i in range(0, len(configs), chunk_size)]
    todo = [i for i in range(len(chunks)) if read_entry(*_chunk(work, key, i, chunks[i])) is None]
    bar = tqdm(total=len(configs), unit="cfg", disable=not progress or None, desc=p.linkage_type,
               initial=sum(len(chunks[i]) for i in range(len(chunks)) if i not in set(todo)))
    with bar:
        if todo:
            if bases is None:
                if on_stage:
                    on_stage(f"unit solutions (estimate for the whole sweep: {cost.seconds / 60:.0f} min, "
                             f"{cost.gib:.2g} GiB)")
                bar.set_postfix_str("unit solutions")
                bases = build_bases(p, solver, workers)
                bar.set_postfix_str("")
            if distributed is None:
                distributed = workers > 1 or scheduler is not None
            if distributed:
                if on_stage:
                    on_stage(f"configurations, {len(todo)} chunks on Dask")
                _run_dask(chunks, todo, p, bases, work, key, workers, scheduler, bar)
            else:
                for k, i in enumerate(todo):
                    if on_stage:
                        on_stage(f"configurations, chunk {k + 1} of {len(todo)}")
                    _write_chunk(work, key, i, chunks[i], run_chunk(chunks[i], p, bases))
                    bar.update(len(chunks[i]))
    timing = work / "timing.json"
    spent = json.loads(timing.read_text())["seconds"] if timing.is_file() else 0.0
    if todo:  # compute time over every run that computed chunks of this sweep
        spent += time.perf_counter() - t0
        with whole_file(timing) as tmp:
            tmp.write_text(json.dumps({"seconds": spent}))
    table = pd.concat([pd.read_csv(_chunk(work, key, i, chunks[i])[0] / "rows.csv", keep_default_na=False,
                                   na_values=[""])
                       for i in range(len(chunks))], ignore_index=True)
    table = table[_column_order(list(table.columns), p)]
    table.attrs["compute_seconds"] = spent or None
    return table


#: seconds a scheduler has to accept a connection before the sweep gives up
CONNECT_TIMEOUT_S = 5.0


def check_scheduler(address: str) -> tuple[str, int]:
    """Host and port of a ``tcp://HOST:PORT`` scheduler address; InputError otherwise (port 1-65535)."""
    m = re.fullmatch(r"tcp://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):([0-9]{1,10})", str(address))
    if not m:
        raise InputError(f"--scheduler = {str(address)[:120]!r} must be tcp://HOST:PORT (e.g. tcp://127.0.0.1:8786)")
    port = int(m.group(2))
    if not 1 <= port <= 65535:
        raise InputError(f"--scheduler port = {port} is outside the allowed range [1, 65535]")
    return m.group(1).strip("[]"), port


def reach_scheduler(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """Connect to the scheduler once, within ``timeout`` s, before any heavy work: ComputeError
    (one line) if nothing answers there."""
    host, port = check_scheduler(address)
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as exc:
        why = "no answer" if isinstance(exc, TimeoutError) else (exc.strerror or type(exc).__name__)
        raise ComputeError(f"cannot reach the Dask scheduler at {address}: {why} (waited at most "
                           f"{timeout:g} s); start it or fix --scheduler") from None
    if not _is_scheduler(address, timeout):  # something answers TCP there (e.g. a proxy): not Dask
        raise ComputeError(f"{address} answers, but not as a Dask scheduler (its identity call failed within "
                           f"{timeout:g} s); start the scheduler there or fix --scheduler")


def _is_scheduler(address: str, timeout: float) -> bool:
    """True if a Dask scheduler answers its identity call at ``address`` within ``timeout`` s."""
    import asyncio

    from distributed.core import rpc

    async def identity() -> dict:
        r = rpc(address, timeout=timeout)
        try:
            return await asyncio.wait_for(r.identity(), timeout)
        finally:
            await r.close_rpc()

    try:
        return asyncio.run(identity()).get("type") == "Scheduler"
    except Exception:  # garbage, a closed stream, a timeout: whatever answers is not a scheduler
        return False



def _run_dask(chunks, todo, p, bases, work, key, workers, scheduler, bar) -> None:
    from contextlib import nullcontext

    import dask
    from dask.distributed import Client, LocalCluster, as_completed

    # Dask's nannies set MALLOC_TRIM_THRESHOLD_ in their workers, which turns off glibc's adaptive
    # mmap threshold: every temporary of the superposition is then mapped and unmapped afresh, at
    # a cost in page faults (benchmarks/bench_malloc_trim.py); the local workers go without it
    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
        local = (LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                              dashboard_address=None) if scheduler is None else nullcontext())
    maps = tempfile.TemporaryDirectory(prefix="rigfem-bases-") if scheduler is None else nullcontext()
    # a remote scheduler is given a connect timeout; a local cluster keeps Dask's default
    connect = {"timeout": CONNECT_TIMEOUT_S} if scheduler else {}
    with maps as folder, local as cluster, Client(scheduler or cluster, **connect) as client:  # the client closes first
        if folder is not None:  # same machine: the workers map one copy of the unit fields
            bases = {key: mapped(b, Path(folder)) for key, b in bases.items()}
        [shared] = client.scatter([bases], broadcast=True)  # unit solutions shipped once per worker
        futures = {client.submit(run_chunk, chunks[i], p, shared, pure=False): i for i in todo}
        for fut in as_completed(futures):
            i = futures.pop(fut)
            _write_chunk(work, key, i, chunks[i], fut.result())
            bar.update(len(chunks[i]))
