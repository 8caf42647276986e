"""Sweep every rig configuration: rules, dynamics and part stresses by superposition.

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
import json
import re
import socket
import tempfile
import time
from pathlib import Path

import numpy as np

from rigfem.dynamics.cycle import simulate
from rigfem.dynamics.history import peaks
from rigfem.cache import Cache
from rigfem.context import Context, default_context
from rigfem.errors import ComputeError, InputError, check_range
from rigfem.linkage.mechanisms import four_bar, slider_crank
from rigfem.loads.cases import part_cases
from rigfem.settings import CheckSettings
from rigfem.verdict.part import judge
from rigfem.mesh.mesher import MACHINE_GIB
from rigfem.sweep.cost import check_cost, sweep_cost
from rigfem.sweep.bases import UnitBasis, build_bases, case_key, mapped
from rigfem.sweep.superpose import case_outcome
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
    verdicts = judge([case_outcome(bases[case_key(case)], case, mode) for mode, case in part_cases(h, pk, s)], s)
    for pv in verdicts.parts:  # the check's own verdict stage: measured band, lost-load guard, unloaded parts
        o, v = pv.outcome, pv.verdict
        row[f"{o.name}_{o.mode}_mpa"] = o.peak_mpa
        row[f"{o.name}_{o.mode}_deg"] = o.crank_deg
        row[f"{o.name}_{o.mode}_band_pct"] = v.error_pct
        row[f"{o.name}_{o.mode}_util_pct"] = v.utilisation_pct
    worst = verdicts.governing
    row["limiting_part"] = f"{worst.outcome.name} ({worst.outcome.mode})" if worst else ""
    row["max_util_pct"] = worst.verdict.utilisation_pct if worst else 0.0
    row["verdict"] = verdicts.stress  # pass, fail or undecided, as rigfem check judges the same outcomes
    return row


# ----------------------------------------------------------------------------- chunks, resume, Dask
def run_chunk(configs: list[dict], p: SweepParams, bases: dict[tuple, UnitBasis] | None) -> list[dict]:
    """Table rows of a chunk of configurations (what a Dask task runs)."""
    s = p.settings()
    rows = [evaluate(c, p, bases, s) for c in configs]
    for r in rows:
        bad = [k for k, v in r.items() if isinstance(v, float) and not np.isfinite(v)]
        if bad:
            raise ComputeError(f"configuration {configs[0]}: non-finite {', '.join(bad)}")
    return rows


def _timed_chunk(configs: list[dict], p: SweepParams, bases) -> tuple[list[dict], float]:
    """:func:`run_chunk` and its compute seconds (a Dask task)."""
    t0 = time.perf_counter()
    return run_chunk(configs, p, bases), time.perf_counter() - t0


def _column_order(cols: list[str], p: SweepParams) -> list[str]:
    lead = ["type", *LENGTHS[p.linkage_type]]
    rules = [c for c in cols if c.startswith("rule")]
    tail = ["limiting_part", "max_util_pct", "verdict"]
    rest = [c for c in cols if c not in lead + rules + tail]
    return [c for c in lead + rules + rest + tail if c in cols]


def _chunk_inputs(key: str, configs: list[dict]) -> dict:
    """The inputs of a stored chunk of the sweep ``key`` (a verified cache entry, kind
    ``sweep_chunks``: a damaged chunk is computed again, never read)."""
    return {"sweep": key, "configs": configs}


def _store_chunk(cache: Cache, key: str, configs: list[dict], rows: list[dict], seconds: float) -> None:
    import pandas as pd

    text = pd.DataFrame(rows).to_csv(index=False, float_format="%.10g")

    def save(tmp: Path) -> None:
        (tmp / "rows.csv").write_text(text)
        (tmp / "seconds.json").write_text(json.dumps(seconds))

    if not cache.put("sweep_chunks", _chunk_inputs(key, configs), save) and \
            not cache.has("sweep_chunks", _chunk_inputs(key, configs)):
        raise ComputeError(f"could not store a sweep chunk in {cache.folder} (disk full or not writable?)")


def _stored_chunk(cache: Cache, key: str, configs: list[dict]) -> tuple[object, float] | None:
    """(rows as a DataFrame, compute seconds) of a stored chunk, or None."""
    import io

    import pandas as pd

    return cache.get("sweep_chunks", _chunk_inputs(key, configs),
                     lambda e: (pd.read_csv(io.StringIO(e.text("rows.csv")), keep_default_na=False, na_values=[""]),
                                float(e.json("seconds.json"))),
                     lambda got: "" if len(got[0]) == len(configs) else "not one row per configuration")


@dataclasses.dataclass(frozen=True)
class SweepOptions:
    """How a sweep runs: configurations per stored chunk (1-100000), on Dask or not (None: when the
    context has more than one worker or a ``scheduler`` ``tcp://HOST:PORT`` is given), only some
    configurations (None: every one on the rig), unit bases already built, and the memory limit the
    job's estimate is held against (GiB)."""

    chunk_size: int = 64
    scheduler: str | None = None
    distributed: bool | None = None
    configs: tuple | None = None
    bases: dict | None = None
    machine_gib: float = MACHINE_GIB

    def __post_init__(self) -> None:
        check_range("chunk_size", self.chunk_size, 1, 100_000)
        if self.scheduler is not None:
            Scheduler(self.scheduler)


#: the keywords of run_sweep before 0.2 that SweepOptions and Context now hold
_OLD_OPTIONS = ("chunk_size", "scheduler", "distributed", "configs", "bases", "machine_gib")
_OLD_CONTEXT = ("workers", "solver")


def old_call(work_dir, old: dict) -> tuple[Context, SweepOptions]:
    """The Context and SweepOptions of a call in the form before 0.2, ``run_sweep(p, work_dir,
    chunk_size=..., workers=..., scheduler=...)``, with a DeprecationWarning: the finished chunks now
    live in the cache (``work_dir`` is not used); ``progress`` and ``on_stage`` are the observer's."""
    import warnings

    from rigfem.cache import from_environment

    warnings.warn("run_sweep(p, work_dir, **keywords) is deprecated: pass a rigfem.context.Context and "
                  "rigfem.sweep.SweepOptions (finished chunks live in the cache, not in work_dir); the old "
                  "form goes in rigfem 0.3", DeprecationWarning, stacklevel=3)
    unknown = set(old) - set(_OLD_OPTIONS) - set(_OLD_CONTEXT) - {"progress", "on_stage"}
    if unknown:
        raise TypeError(f"run_sweep() got unexpected keyword arguments {sorted(unknown)}")
    opts = {k: (tuple(v) if k == "configs" and v is not None else v) for k, v in old.items() if k in _OLD_OPTIONS}
    ctx = Context(cache=from_environment(), **{k: v for k, v in old.items() if k in _OLD_CONTEXT})
    return ctx, SweepOptions(**opts)


def run_sweep(p: SweepParams, ctx: Context | None = None, options: SweepOptions = SweepOptions(), **old):
    """Run (or resume) a sweep; return the table (pandas DataFrame, one row per configuration).

    Finished chunks are stored in ``ctx.cache`` (with the unit bases, meshes and solutions), so a
    later run of the same sweep reads them; with no cache everything is computed and nothing
    resumes (no context: the environment's cache; the form before 0.2, ``run_sweep(p, work_dir,
    **keywords)``, still runs, with a DeprecationWarning: :func:`old_call`).  On Dask, a
    LocalCluster with ``ctx.workers`` processes runs inside this process unless
    ``options.scheduler`` names an existing cluster; with ``ctx.workers`` > 1 the unit bases are
    built two geometries at a time (:func:`~rigfem.sweep.bases.build_bases`).  The job's cost is
    estimated from the counts before any work (:mod:`rigfem.sweep.cost`; past
    ``options.machine_gib`` or the time limit: InputError).  ``ctx.observer`` hears each stage and
    the configurations done.
    """
    import pandas as pd

    if old or (ctx is not None and not isinstance(ctx, Context)):  # the form before 0.2
        ctx, options = old_call(ctx, old)
    ctx = default_context(ctx)
    cache, observer, workers = ctx.cache, ctx.observer, ctx.workers  # (Context holds workers in 1-256)
    configs = enumerate_configs(p) if options.configs is None else list(options.configs)
    bases, scheduler = options.bases, options.scheduler
    cost = sweep_cost(p, configs, workers, bases=bases is None)
    check_cost(cost, options.machine_gib)  # from the counts, before anything is built
    if scheduler is not None and options.distributed is not False:
        reach_scheduler(scheduler)  # in seconds, before the unit solutions are built
    key = p.key()
    size = options.chunk_size
    chunks = [configs[i:i + size] for i in range(0, len(configs), size)]
    done = {i: got for i in range(len(chunks)) if (got := _stored_chunk(cache, key, chunks[i])) is not None}
    todo = [i for i in range(len(chunks)) if i not in done]
    count = [sum(len(chunks[i]) for i in done)]

    def finished(i: int, rows: list[dict], seconds: float) -> None:
        _store_chunk(cache, key, chunks[i], rows, seconds)
        done[i] = (pd.DataFrame(rows), seconds)
        count[0] += len(chunks[i])
        observer.step(count[0], len(configs), f"{p.linkage_type} configurations")

    if todo:
        t0 = time.perf_counter()
        if bases is None:
            observer.stage(f"unit solutions (estimate for the whole sweep: {cost.seconds / 60:.0f} min, "
                           f"{cost.gib:.2g} GiB)")
            bases = build_bases(p, ctx.solver, workers, cache=cache)
        per = (time.perf_counter() - t0) / len(todo)  # the bases' time, shared by the chunks computed
        distributed = options.distributed
        if distributed is None:
            distributed = workers > 1 or scheduler is not None
        if distributed:
            observer.stage(f"configurations, {len(todo)} chunks on Dask")
            _run_dask(chunks, todo, p, bases, workers, scheduler, lambda i, rows, s: finished(i, rows, s + per))
        else:
            for k, i in enumerate(todo):
                observer.stage(f"configurations, chunk {k + 1} of {len(todo)}")
                t1 = time.perf_counter()
                rows = run_chunk(chunks[i], p, bases)
                finished(i, rows, time.perf_counter() - t1 + per)
    table = pd.concat([done[i][0] for i in range(len(chunks))], ignore_index=True)
    table = table[_column_order(list(table.columns), p)]
    spent = sum(done[i][1] for i in range(len(chunks)))
    table.attrs["compute_seconds"] = spent or None
    return table


#: seconds a scheduler has to accept a connection before the sweep gives up
CONNECT_TIMEOUT_S = 5.0


@dataclasses.dataclass(frozen=True)
class Scheduler:
    """A Dask scheduler's ``tcp://HOST:PORT`` address, checked as it is made (port 1-65535)."""

    address: str
    host: str = dataclasses.field(init=False, compare=False)
    port: int = dataclasses.field(init=False, compare=False)

    def __post_init__(self) -> None:
        m = re.fullmatch(r"tcp://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):([0-9]{1,10})", str(self.address))
        if not m:
            raise InputError(f"--scheduler = {str(self.address)[:120]!r} must be tcp://HOST:PORT "
                             f"(e.g. tcp://127.0.0.1:8786)")
        port = int(m.group(2))
        if not 1 <= port <= 65535:
            raise InputError(f"--scheduler port = {port} is outside the allowed range [1, 65535]")
        object.__setattr__(self, "host", m.group(1).strip("[]"))
        object.__setattr__(self, "port", port)


def check_scheduler(address: str) -> tuple[str, int]:
    """Host and port of a ``tcp://HOST:PORT`` scheduler address (:class:`Scheduler`: InputError
    otherwise, port 1-65535)."""
    s = Scheduler(address)
    return s.host, s.port


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



def _run_dask(chunks, todo, p, bases, workers, scheduler, finished) -> None:
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
        futures = {client.submit(_timed_chunk, chunks[i], p, shared, pure=False): i for i in todo}
        for fut in as_completed(futures):
            i = futures.pop(fut)
            finished(i, *fut.result())
