"""Mesh convergence of a check's peak von Mises: h- and p-refinement, Richardson extrapolation.

For a part case of a scene (both modes share one mesh per step) :func:`study` runs

* an **h sequence**: order 2 (or 1), global and local mesh size scaled together by ``ratio`` per level,
  ending at ``finest`` (default the ``fine`` preset's sizes), plus finer levels while the peak is
  not converging (at most ``extend``);
* the **presets** ``draft`` and ``standard`` (the h sequence passes ``fine``'s sizes by default);
* a **p step**: order 1 on the ``standard`` mesh, beside order 2 on the same mesh.

Every step reports, per mode, the check's peak (max over the crank cycle of the superposed
unit solutions), DOFs, wall time (``time.perf_counter`` around mesh + assembly + solves +
superposition, meshing uncached), the process's CPU time over the same span, and peak
memory.  Memory is the peak RSS (VmHWM) of a fresh process per step (spawned), because the
dominant allocations (gmsh, PARDISO/MKL factors) are native and invisible to ``tracemalloc``;
the process's peak RSS after imports is reported beside it.

:func:`richardson` extrapolates the three finest levels (general refinement ratios, fixed-point
iteration as in Celik et al. 2008), gives the observed order and the GCI, and flags a peak whose
successive differences do not shrink or give an order ≤ 0 as **not converging** (a
singularity): such a peak has no extrapolated value and no preset can meet a target on it.
Two cases have no Richardson limit but are not singular, and are reported as such with the
finest level as reference and an explicit uncertainty: a sequence that alternates with
shrinking differences (``oscillating``: the limit lies between the last two levels), and one
whose last two changes are both below :data:`NOISE` of the value and do not grow
(``noise-limited``: unstructured remeshing moves the peak node by more than the discretisation
error left).  A peak that keeps rising level after level is never noise-limited.

A peak that is not converging at the finest preset may be singular or only pre-asymptotic (a
small fillet resolved by a few elements at the presets' sizes).  :func:`study` then adds up to
``extend`` finer levels (same ratio, within ``max_gib``): a singular peak keeps rising, a smooth
one settles.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import resource
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import get_context

import numpy as np

from rigfem.cache import Cache
from rigfem.job import Job, Request, read_job
from rigfem.observer import SILENT, Observer
from rigfem.errors import ComputeError, InputError, check_range
from rigfem.mesh.mesher import estimate
from rigfem.settings import FIDELITY, PRESET_ERROR_PCT

#: default refinement ratio between h levels (local and global size)
RATIO = 2 ** 0.5


#: bearing directions of every h-sequence step (the finest preset's), so only the mesh changes
H_DIRECTIONS = FIDELITY["fine"].bearing_directions


#: accuracy targets against the extrapolated peak, per preset (issue 6)
TARGETS = {k: v / 100 for k, v in PRESET_ERROR_PCT.items()}


#: relative change between the finest levels below which a non-growing peak is remeshing noise
NOISE = 0.01


#: radius (mm) around the sharp web-flange corners of an unfilleted I-profile (fillet_radius = 0)
#: excluded from the second quantity ("peak away from the singular edges")
AWAY_MM = 4.0


#: finer h levels added beyond the finest while a peak is not converging (memory permitting)
EXTEND = 1


@dataclasses.dataclass
class Extrapolation:
    """Richardson extrapolation of the three finest levels of a sequence."""

    converging: bool
    limit: float | None  #: extrapolated peak (None when not converging)
    order: float | None  #: observed order of convergence (in h)
    orders: list[float | None]  #: observed order of every triple, coarse to fine (< 0: oscillating)
    asymptotic: bool  #: the last two triples' orders agree within 30 % (needs ≥ 4 levels)
    gci: float | None  #: relative uncertainty of the limit: GCI of the finest level (Roache, Fs = 1.25)
    status: str  #: converged | oscillating | noise-limited | round-off | not converging
    note: str

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def _order(h: Sequence[float], q: Sequence[float]) -> tuple[float | None, str]:
    """Observed order of a triple (coarse → fine), or None with the reason it does not converge."""
    e21, e32 = q[1] - q[0], q[2] - q[1]
    scale = max(abs(v) for v in q) or 1.0
    if abs(e21) <= 1e-12 * scale and abs(e32) <= 1e-12 * scale:
        return math.inf, "converged to round-off"
    if abs(e32) >= abs(e21):
        return None, "successive differences do not shrink (singular peak)"
    if e32 / e21 < 0.0:
        return -math.log(abs(e21 / e32)) / math.log(h[1] / h[2]), "oscillating"
    r21, r32 = h[0] / h[1], h[1] / h[2]
    # q = L + C h^p  =>  e21/e32 = r32^p (r21^p - 1)/(r32^p - 1); fixed point from the constant-ratio p
    p = math.log(abs(e21 / e32)) / math.log(r32)
    for _ in range(200):
        if p <= 0.0:
            break
        p_new = (math.log(abs(e21 / e32)) - math.log((r21 ** p - 1.0) / (r32 ** p - 1.0))) / math.log(r32)
        if abs(p_new - p) < 1e-13:
            p = p_new
            break
        p = p_new
    if not math.isfinite(p) or p <= 0.0:
        return None, "observed order ≤ 0 (singular peak)"
    return p, ""


def richardson(h: Sequence[float], q: Sequence[float]) -> Extrapolation:
    """Extrapolate a quantity ``q`` over mesh sizes ``h`` (both coarse → fine) from its last three.

    Converging needs monotone, shrinking differences and an observed order > 0; the limit is
    ``q3 + (q3 − q2)/(r32^p − 1)``.
    """
    h, q = [float(v) for v in h], [float(v) for v in q]
    if len(h) != len(q) or len(q) < 3:
        raise ComputeError(f"Richardson extrapolation needs at least 3 levels, got {len(q)}")
    if any(not math.isfinite(v) for v in h + q) or any(b >= a for a, b in zip(h, h[1:])) or h[-1] <= 0:
        raise ComputeError("Richardson extrapolation needs finite values and mesh sizes > 0 decreasing "
                         "coarse → fine")
    orders = [_order(h[i:i + 3], q[i:i + 3])[0] for i in range(len(q) - 2)]
    p, why = _order(h[-3:], q[-3:])
    clean = [None if o is None or math.isinf(o) else o for o in orders]  # negative: oscillating
    if p is None:
        e21, e32 = q[-2] - q[-3], q[-1] - q[-2]
        growing = e21 * q[-1] > 0 and e32 * q[-1] > 0  # |q| rises level after level: a singularity
        if not growing and max(abs(e21), abs(e32)) <= NOISE * abs(q[-1]):
            u = 1.25 * max(abs(e21), abs(e32)) / abs(q[-1])
            return Extrapolation(True, q[-1], None, clean, False, u, "noise-limited",
                                 f"changes of the finest levels ≤ {100 * NOISE:g} % and not growing: "
                                 "remeshing noise, no Richardson limit; reference = finest level, "
                                 "uncertainty = 1.25 × the larger of its last two changes")
        return Extrapolation(False, None, None, clean, False, None, "not converging", why)
    if math.isinf(p):
        return Extrapolation(True, q[-1], None, clean, True, 0.0, "round-off", why)
    if p < 0:  # shrinking but alternating: the limit lies between the last two levels
        return Extrapolation(True, q[-1], None, clean, False, abs((q[-1] - q[-2]) / q[-1]), "oscillating",
                             "oscillating with shrinking differences (|order| "
                             f"{-p:.2f}): no Richardson limit; reference = finest level, uncertainty "
                             "(gci) = its last change")
    r32 = h[-2] / h[-1]
    limit = q[-1] + (q[-1] - q[-2]) / (r32 ** p - 1.0)
    gci = 1.25 * abs((q[-1] - q[-2]) / q[-1]) / (r32 ** p - 1.0) if q[-1] else None
    asym = len(q) >= 4 and clean[-2] is not None and clean[-2] > 0 and abs(clean[-2] - p) <= 0.3 * p
    note = "" if asym else "3 levels: asymptotic range unchecked" if len(q) < 4 else \
        "order of the previous triple differs: not yet in the asymptotic range, extrapolation uncertain"
    return Extrapolation(True, limit, p, clean, asym, gci, "converged", note)


@dataclasses.dataclass(frozen=True)
class StepSpec:
    """One mesh/order setting of a study."""

    label: str  #: e.g. "h1", "draft", "P1@standard"
    kind: str  #: "h", "preset" or "p"
    order: int
    size_mm: float
    local_size_mm: float
    bearing_directions: int


def away_from_singular_edges(part_name: str, params: dict | None, nodes: np.ndarray,
                             away_mm: float = AWAY_MM) -> np.ndarray | None:
    """Mask of points (n, 3) farther than ``away_mm`` from the sharp re-entrant web-flange corners
    of an I-profile without root fillets; None for any other part, a filleted I-profile included
    (no singular edge: its base rests on a normal-only support, which a mirror image of the part
    continues smoothly, and its bolts are elastic foundations)."""
    from rigfem.rig.parts import load_part

    part = load_part(part_name, params or None)
    if part.kind != "iprofile" or part["fillet_radius"] > 0:
        return None
    tw, tf, h = part["web_thickness"], part["flange_thickness"], part["height"]
    y, z = np.abs(nodes[:, 1]) - tw / 2, nodes[:, 2]
    return np.minimum(np.hypot(y, z - tf), np.hypot(y, z - (h - tf))) > away_mm


def _peak_rss_mib() -> float:
    """Peak resident memory of this process image (VmHWM; ``ru_maxrss`` would include the RSS of
    the parent at fork time, which survives the spawn's exec)."""
    try:
        with open("/proc/self/status") as f:
            return next(int(x.split()[1]) for x in f if x.startswith("VmHWM:")) / 1024
    except (OSError, StopIteration):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _cpu() -> float:
    """CPU seconds of this process, all threads (wall time alone misleads on a shared machine)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _run_step(cases: list, settings, spec: StepSpec, isolate: bool) -> dict:
    """Solve the cases at one setting: peaks per mode, DOFs, seconds, memory (in this process)."""
    from rigfem.context import Context
    from rigfem.fe.executor import Plan, solve_cases
    from rigfem.tensors import von_mises

    rss0 = _peak_rss_mib()
    for _, c in cases:  # a cycle case carries its unit bearing loads in exactly n_dir directions
        n = len({u.direction for u in c.loads if u.kind == "bearing"})
        if len(c.rows) > 1 and n != spec.bearing_directions:
            raise ValueError(f"step {spec.label}: {c.name} was built with {n} bearing directions, "
                             f"not {spec.bearing_directions}")
    s = dataclasses.replace(settings, order=spec.order, size_mm=spec.size_mm,
                            local_size_mm=spec.local_size_mm, bearing_directions=spec.bearing_directions)
    with tempfile.TemporaryDirectory(prefix="rigfem-conv-") as folder:  # every step meshed afresh: its
        t0, c0 = time.perf_counter(), _cpu()                              # time is part of the cost
        results = solve_cases(cases, s, Plan(frames=None), Context(Cache(Path(folder), 1 << 62)))
        seconds, cpu = time.perf_counter() - t0, _cpu() - c0
    modes = {}
    for r in results:
        S = r.solution.nodal_stress
        pk = r.peak
        entry = {"peak_mpa": float(pk.value), "crank_deg": float(r.case.rows[r.row]), "surface": pk.surface,
                 "xyz": [round(float(v), 3) for v in pk.xyz], "zz_error": float(pk.zz_error)}
        mask = away_from_singular_edges(r.case.part, r.case.params, r.solution.model.mesh.nodes)
        if mask is not None:
            sub = S[:, mask]
            away = max(float(von_mises(np.tensordot(r.coef[i:i + 24], sub, 1)).max())
                       for i in range(0, len(r.coef), 24))
            entry["away_mpa"] = away
        modes[r.mode] = entry
    if not all(math.isfinite(v) for m in modes.values() for k, v in m.items() if k.endswith("_mpa")):
        raise RuntimeError(f"step {spec.label}: non-finite peak")
    mem = _peak_rss_mib() if isolate else None
    return {**dataclasses.asdict(spec), "modes": modes, "dofs": int(results[0].solution.model.mesh.ndof),
            "tets": int(len(results[0].mesh.tets)), "seconds": seconds, "cpu_seconds": cpu,
            "peak_rss_mib": mem, "base_rss_mib": rss0 if isolate else None, "load_avg": os.getloadavg()[0]}


def run_step(cases: list, settings, spec: StepSpec, isolate: bool = True) -> dict:
    """One step, in a fresh spawned process (``isolate``: memory measured) or in this one."""
    if not isolate:
        return _run_step(cases, settings, spec, False)
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as ex:
        return ex.submit(_run_step, cases, settings, spec, True).result()


def h_levels(levels: int, ratio: float = RATIO, finest: tuple[float, float] | None = None,
             order: int = 2, beyond: int = 0) -> list[StepSpec]:
    """The h sequence coarse → fine: (global, local) size × ratio^k, level ``levels - 1`` at
    ``finest``, then ``beyond`` finer levels (run only while a peak is not converging)."""
    g, loc = finest or (FIDELITY["fine"].size_mm, FIDELITY["fine"].near_mm)
    return [StepSpec(f"h{k}", "h", order, g * ratio ** (int(levels) - 1 - k), loc * ratio ** (int(levels) - 1 - k),
                     H_DIRECTIONS) for k in range(int(levels) + max(int(beyond), 0))]


def preset_steps() -> list[StepSpec]:
    """draft and standard as presets, and order 1 on the standard mesh (the p step)."""
    out = [StepSpec(n, "preset", f.order, f.size_mm, f.near_mm, f.bearing_directions)
           for n, f in FIDELITY.items() if n != "fine"]
    st = FIDELITY["standard"]
    out.append(StepSpec("P1@standard", "p", 1, st.size_mm, st.near_mm, st.bearing_directions))
    return out


def _predicted_gib(prev: dict | None, spec: StepSpec) -> float:
    """Memory of a step predicted from the previous (coarser) one: tets scale with size^-3."""
    if prev is None:
        return 0.0
    grow = max(prev["size_mm"] / spec.size_mm, prev["local_size_mm"] / spec.local_size_mm) ** 3
    return estimate(int(prev["tets"] * grow)).gib


@dataclasses.dataclass(frozen=True)
class StudySpec:
    """How a convergence study runs: ``levels`` h levels (3-8) ``ratio`` apart (1.1-2) ending at
    ``finest`` (global, local size mm; default the ``fine`` preset's) at element ``order``, up to
    ``extend`` finer ones while a peak is not converging, within ``max_gib`` (0.5-1024 GiB) per
    step; the presets too (``presets``); each step in a fresh process (``isolate``: its memory
    measured); only ``modes`` (None: every mode)."""

    levels: int = 4
    ratio: float = RATIO
    modes: tuple[str, ...] | None = None
    max_gib: float = 12.0
    isolate: bool = True
    presets: bool = True
    finest: tuple[float, float] | None = None
    order: int = 2
    extend: int = EXTEND

    def __post_init__(self) -> None:
        if check_range("--levels", self.levels, 3, 8) != int(self.levels):
            raise InputError(f"--levels = {self.levels!r} must be a whole number in [3, 8]")
        check_range("--ratio", self.ratio, 1.1, 2.0)
        check_range("--max-gib", self.max_gib, 0.5, 1024.0, "GiB")
        check_range("--extra-levels", self.extend, 0, 3)
        if self.order not in (1, 2):
            raise InputError(f"order = {self.order!r} must be 1 or 2")


def study(cases_for: Callable[[int], list], settings, plan: StudySpec = StudySpec(),
          observer: Observer = SILENT) -> dict:
    """Convergence study of one part: ``cases_for(n_dir)`` gives its [(mode, PartCase)] with
    ``n_dir`` bearing directions (see :func:`scene_cases`).  The observer hears each step begin and
    gets the partial result after every step (``observer.partial``: to save progress).  A step
    whose process dies (e.g. killed out of memory) ends the h sequence and is listed in
    ``refused``.  While a peak is not converging, up to ``plan.extend`` finer levels are added
    (:func:`needs_finer`)."""
    modes = plan.modes
    first = [(m, c) for m, c in cases_for(H_DIRECTIONS) if modes is None or m in modes]
    if not first:  # rigfem convergence refuses a --mode the scene's [check].modes lacks
        raise ComputeError(f"modes {list(modes or [])}: no case of this part in that mode")
    name = first[0][1].name
    out = {"part": name, "part_def": first[0][1].part, "params": first[0][1].params, "ratio": plan.ratio,
           "h_directions": H_DIRECTIONS, "fine_is_finest": plan.finest is None and plan.order == 2, "steps": [],
           "refused": []}
    steps, refused = out["steps"], out["refused"]

    def run(spec: StepSpec) -> bool:
        observer.stage(f"part {name}: step {spec.label}")
        cases = [(m, c) for m, c in cases_for(spec.bearing_directions) if modes is None or m in modes]
        try:
            steps.append(run_step(cases, settings, spec, plan.isolate))
        except BrokenProcessPool:
            refused.append(f"{spec.label}: the step's process was killed (out of memory on the shared "
                           f"machine?)")
            return False
        observer.partial(analyse(out) if len([s for s in steps if s["kind"] == "h"]) else out)
        return True

    for k, spec in enumerate(h_levels(plan.levels, plan.ratio, plan.finest, plan.order, beyond=plan.extend)):
        if k >= int(plan.levels) and not needs_finer(analyse(out)):
            break
        need = _predicted_gib(steps[-1] if steps else None, spec)
        if need > plan.max_gib:
            refused.append(f"{spec.label}: about {need:.3g} GiB predicted > --max-gib {plan.max_gib:g}")
            break
        if not run(spec):
            break
    if plan.presets:
        for spec in preset_steps():
            run(spec)
    if not [s for s in steps if s["kind"] == "h"]:
        raise ComputeError(f"{name}: no h level could be solved ({'; '.join(refused)})")
    return analyse(out)


def needs_finer(res: dict) -> bool:
    """True when an analysed study's peak is not converging in some mode (a finer level tells a
    singular peak, which keeps rising, from a pre-asymptotic one)."""
    exs = [m.get("peak_mpa", {}).get("extrapolation") for m in res.get("modes", {}).values()]
    return any(ex is not None and not ex["converging"] for ex in exs)


def fine_step(hs: list[dict]) -> dict | None:
    """The h level at the ``fine`` preset's sizes (P2), if the sequence has one."""
    f = FIDELITY["fine"]
    return next((s for s in hs if s["order"] == f.order and math.isclose(s["size_mm"], f.size_mm)
                 and math.isclose(s["local_size_mm"], f.near_mm)), None)


def analyse(res: dict) -> dict:
    """(Re)compute a study's extrapolation and errors per mode from its steps (in place)."""
    hs = [s for s in res["steps"] if s["kind"] == "h"]
    fine = res.get("fine_is_finest", True)
    part = (res["part_def"], res["params"])
    res["modes"] = {m: _analyse(hs, res["steps"], m, fine, part) for m in res["steps"][0]["modes"]}
    return res


def _analyse(hs: list[dict], steps: list[dict], mode: str, fine_is_finest: bool,
             part: tuple[str, dict] | None = None) -> dict:
    """Extrapolation of the h sequence and every step's error for one mode (and away_mpa)."""
    res = {}
    for qty in ("peak_mpa", "away_mpa"):
        if not hs or qty not in hs[0]["modes"][mode]:
            continue
        if len(hs) < 3:
            res[qty] = {"extrapolation": None, "note": "fewer than 3 levels (memory guard): no extrapolation"}
            continue
        ex = richardson([s["local_size_mm"] for s in hs], [s["modes"][mode][qty] for s in hs])
        fin = hs[-1]["modes"][mode]
        away = None if part is None else away_from_singular_edges(part[0], part[1], np.array([fin["xyz"]]))
        if qty == "peak_mpa" and ex.converging and away is not None and not away[0]:
            ex = Extrapolation(False, None, None, ex.orders, False, None, "not converging",
                               f"the peak sits within {AWAY_MM:g} mm of a sharp re-entrant web-flange corner, "
                               "a geometric singularity (σ ~ r^-0.46 at a 90° re-entrant corner): the "
                               "finite sequence's apparent trend is pre-asymptotic")
        errors, presets = {}, {}
        # oscillating: the reference *is* the finest level, whose own error is only known as ± gci
        own = ex.status in ("oscillating", "noise-limited")
        for s in steps:
            q = s["modes"][mode][qty]
            ok = ex.converging and ex.limit and not (own and s is hs[-1])
            errors[s["label"]] = (q - ex.limit) / ex.limit if ok else None
        named = {s["label"]: s for s in steps if s["kind"] == "preset"}
        fine = fine_step(hs) if fine_is_finest else None
        if fine is not None:
            named["fine"] = fine
        for p, tol in TARGETS.items():
            if p in named:
                e = errors[named[p]["label"]]
                bound = ex.gci if (e is None and own and named[p] is hs[-1]) else None
                presets[p] = {"step": named[p]["label"], "seconds": named[p]["seconds"],
                              "cpu_seconds": named[p].get("cpu_seconds"),
                              "peak_rss_mib": named[p]["peak_rss_mib"], "dofs": named[p]["dofs"],
                              "value": named[p]["modes"][mode][qty], "error": e, "error_bound": bound,
                              "target": tol, "meets": (abs(e) <= tol if e is not None else
                                                       bound <= tol if bound is not None else None)}
        res[qty] = {"extrapolation": ex.as_dict(), "errors": errors, "presets": presets}
    return res


def scene_cases(request: Request, cache: Cache) -> tuple[Job, dict[str, Callable[[int], list]]]:
    """The job and {part: cases_for} of a check's request, ``cases_for(n_dir)`` giving the
    part's [(mode, PartCase)] with ``n_dir`` bearing directions: the check's own stages (the job,
    its motion and reactions, computed once; a scene that breaks a rig rule is refused unless the
    request allows it, as by rigfem check)."""
    from rigfem.dynamics.cycle import react
    from rigfem.linkage.state import linkage_state
    from rigfem.loads.cases import part_cases

    job = read_job(request, cache)
    reactions = react(job.linkage, linkage_state(job.linkage, job.crank_deg, job.scene.speed_hz), job.dynamics)
    if reactions.singular:
        raise ComputeError(f"{job.scene.name}: the linkage passes a toggle (singular) position: its reactions "
                           f"are unbounded there, so no part case can be solved")
    h, pk, s = reactions.history, reactions.peaks, job.settings

    def builder(name: str) -> Callable[[int], list]:
        return lambda n_dir: part_cases(h, pk, dataclasses.replace(s, parts={name: s.parts[name]},
                                                                   bearing_directions=n_dir))
    return job, {name: builder(name) for name in s.parts}


def to_json(result: dict) -> str:
    """JSON text of a study (inf/NaN never written: they are None by construction)."""
    return json.dumps(result, indent=1, allow_nan=False)
