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
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rigfem.dynamics.history import peaks
from rigfem.dynamics.mechanisms import MODELS, four_bar, simulate, slider_crank
from rigfem.errors import ComputeError, InputError, check_range
from rigfem.loads.cases import (
    PartCase,
    UnitLoad,
    directions,
    part_cases,
)
from rigfem.rig.catalogue import RIG_RAILS_MM
from rigfem.rig.layout import RailLayout, rail_layout
from rigfem.rig.parts import rail_hole_name
from rigfem.rig.rules import (
    HOLE_PITCH_MM,
    MIN_GROUND_MM,
    fourbar_rules,
    slider_crank_rules,
)
from rigfem.schema import validate_check
from rigfem.settings import (
    FIDELITY,
    PARTS,
    PLATE,
    PRESET_ERROR_PCT,
    RAIL,
    CheckSettings,
    check_settings,
)
from rigfem.verdict.criterion import half_ultimate, overall

TYPES = ("four-bar", "slider-crank")


#: ground rail length (mm), RIG.md §3
GROUND_RAIL_MM = 2500.0


#: basis directions for bearing loads whose direction is set by the configuration (original mode)
ORIGINAL_DIRECTIONS = 72


#: candidate nodes of each unit field (its highest von Mises)
TOP_NODES = 30


#: groups of crank-angle rows, each with its own stress bound per node (see :func:`case_peak`)
BOUND_GROUPS = 36


#: crank-angle rows superposed at once
ROW_CHUNK = 24


#: joints whose peak reaction the table reports, per linkage type
JOINTS = {"four-bar": ("O2", "A", "B", "O4"), "slider-crank": ("O2", "A", "B", "slide")}


LENGTHS = {"four-bar": ("b2", "b3", "b4", "d"), "slider-crank": ("b2", "b3", "offset")}


@dataclass(frozen=True)
class SweepParams:
    """What a sweep computes; its hash keys the stored chunks."""

    linkage_type: str = "four-bar"
    speed_hz: float = 1.0
    model: str = "rigid-body"
    fidelity: str = "draft"
    samples: int = 360
    rails_mm: tuple[float, ...] = RIG_RAILS_MM
    ground_mm: float = GROUND_RAIL_MM
    check: tuple[tuple[str, object], ...] = ()  #: extra ``[check]`` fields (e.g. coarser test meshes)

    def __post_init__(self) -> None:
        if self.linkage_type not in TYPES:
            raise InputError(f"linkage type = {self.linkage_type!r} must be one of {', '.join(TYPES)}")
        if self.model not in MODELS:
            raise InputError(f"model = {self.model!r} must be one of {', '.join(MODELS)}")
        if self.model == "original" and self.linkage_type != "four-bar":
            raise InputError("model = 'original' exists only for the four-bar; use rigid-body")
        if self.fidelity not in FIDELITY:
            raise InputError(f"fidelity = {self.fidelity!r} must be one of {', '.join(FIDELITY)}")
        check_range("speed_hz", self.speed_hz, 0.0, 100.0, "Hz", lo_open=True)
        check_range("samples", self.samples, 36, 100_000)
        check_range("ground rail length", self.ground_mm, 700.0, 6000.0, "mm")

    @property
    def rails(self) -> tuple[float, ...]:
        """Rail lengths of the linkage type (crank, coupler/rod, rocker)."""
        return tuple(self.rails_mm[:3] if self.linkage_type == "four-bar" else self.rails_mm[:2])

    def settings(self) -> CheckSettings:
        # tuples keep the params hashable; the scene schema takes lists
        table = {"fidelity": self.fidelity, **{k: list(v) if isinstance(v, tuple) else v for k, v in self.check}}
        validate_check(table, "sweep")
        return check_settings(table, self.linkage_type, list(self.rails))

    def key(self) -> str:
        """Short hash of the parameters and of everything else a stored chunk depends on: the
        part files, the mass catalogue and the source files that compute a row (a change to any
        of them must not resume from chunks computed before it)."""
        from rigfem.fe.cache import SOLUTION_CODE
        from rigfem.mesh.cache import code_hash
        from rigfem.rig.catalogue import RIG_MASSES
        from rigfem.rig.parts import load_part

        parts = sorted({spec["part"] for spec in PARTS[self.linkage_type].values()})
        src = dict(dataclasses.asdict(self), orig_dirs=ORIGINAL_DIRECTIONS,
                   parts={n: load_part(n).content_hash() for n in parts},
                   masses=dataclasses.asdict(RIG_MASSES),
                   code=code_hash(*SOLUTION_CODE, "studies/sweep.py", "dynamics/*.py", "loads/*.py", "rig/*.py",
                                  "verdict/*.py", "settings.py", "schema.py", "fe/partcase.py", "fe/tensors.py"))
        return hashlib.sha256(json.dumps(src, sort_keys=True).encode()).hexdigest()[:12]


# ----------------------------------------------------------------------------- enumeration
def _layout(length_mm: float) -> RailLayout:
    return rail_layout(RAIL, length_mm, PLATE)


def rail_lengths(length_mm: float, first: float = HOLE_PITCH_MM) -> list[float]:
    """Joint distances (mm) on the 60 mm grid from ``first`` whose coupling lands on holes."""
    lay = _layout(length_mm)
    out, b = [], first
    while True:
        try:
            lay.coupling(b, "rail")
        except InputError:
            return out
        out.append(b)
        b += HOLE_PITCH_MM


def enumerate_configs(p: SweepParams) -> list[dict]:
    """Every mountable configuration: each length on the hole grid within its rail (RIG.md §1-2).

    Four-bar: b2, b3, b4 on their rails, d on the ground rail from 660 mm (the rule; shorter
    ground lengths collide and are not enumerated).  Slider-crank: b2, b3 on their rails,
    slide line through O2 (offset 0: the ground rail carries both).
    """
    ground = [d for d in rail_lengths(p.ground_mm) if d >= MIN_GROUND_MM]
    if p.linkage_type == "four-bar":
        b2s, b3s, b4s = (rail_lengths(r) for r in p.rails)
        return [dict(b2=b2, b3=b3, b4=b4, d=d) for b2 in b2s for b3 in b3s for b4 in b4s for d in ground]
    b2s, b3s = (rail_lengths(r) for r in p.rails)
    return [dict(b2=b2, b3=b3, offset=0.0) for b2 in b2s for b3 in b3s if b2 + b3 <= max(ground)]


def _slug(name: str) -> str:
    return re.sub(r"[^a-z0-9]+", "_", name.split("(")[0].strip().lower()).strip("_")


def rules_row(p: SweepParams, cfg: dict) -> dict:
    """Every rig rule of a configuration: value and pass/fail columns, and whether all pass."""
    lengths = {k: cfg[k] for k in LENGTHS[p.linkage_type]}  # a cfg may also name its branch
    rules = fourbar_rules(**lengths) if p.linkage_type == "four-bar" else slider_crank_rules(**lengths)
    row = {}
    for r in rules:
        row[f"rule_{_slug(r.name)}"] = round(r.value, 6)
        row[f"rule_{_slug(r.name)}_ok"] = r.ok
    row["rules_ok"] = all(r.ok for r in rules)
    return row


# ----------------------------------------------------------------------------- FE unit bases
@dataclass
class UnitBasis:
    """Unit stress fields of one part geometry and support set (float32, every node)."""

    key: tuple
    loads: list[UnitLoad]
    groups: dict[str, tuple[np.ndarray, np.ndarray]]  #: group -> (angles rad sorted, columns)
    inertia: dict[tuple, int]  #: (component, origin) -> column
    S: np.ndarray  #: (k, N, 6) float32 nodal stress of every unit load
    vm: np.ndarray  #: (k, N) float32 von Mises of every unit field (the bound of ``case_peak``)
    top: np.ndarray  #: (k, TOP_NODES) the nodes where each unit field is highest
    fe_mass: float  #: kg, mass of the meshed part


def _case_key(case: PartCase) -> tuple:
    return case.part, tuple(sorted(case.params.items())), tuple(case.supports)


def _reference_cases(p: SweepParams, s: CheckSettings) -> list[tuple[str, PartCase]]:
    """The cases of the first configuration that runs (its parts, supports and load groups)."""
    from rigfem.dynamics.linkage import AssemblyError, ClosureError

    q = dataclasses.replace(p, samples=36)
    for cfg in enumerate_configs(p):
        try:
            with np.errstate(divide="ignore", invalid="ignore"):
                lk = four_bar(**cfg, rails_mm=p.rails) if p.linkage_type == "four-bar" else \
                    slider_crank(**cfg, rails_mm=p.rails)
                h = simulate(lk, samples=q.samples, speed_hz=q.speed_hz, model=q.model)
        except (ClosureError, AssemblyError):
            continue
        pk = peaks(h)
        if not h.meta.get("singular") and not any(v.get("singular") for v in pk.values()):
            return part_cases(h, pk, s)
    raise InputError(f"no {p.linkage_type} configuration of rails {list(p.rails)} mm can run")


def _basis_specs(p: SweepParams, s: CheckSettings) -> dict[tuple, tuple[PartCase, list[UnitLoad]]]:
    """Per (part, params, supports): a template case (mesh, supports, refinement) and every unit
    load any configuration can use.  Supports, load groups and inertia loads come from the
    load-case functions themselves (a reference configuration); only the sets are widened:
    a rail's coupling may use any hole in cycle mode, and bearing directions span the basis."""
    specs: dict[tuple, tuple[PartCase, list[UnitLoad]]] = {}
    ncyc, norig = directions(s.bearing_directions), directions(ORIGINAL_DIRECTIONS)
    for mode, case in _reference_cases(p, s):
        groups = list(dict.fromkeys(u.group for u in case.loads if u.kind == "bearing"))
        refine = tuple(case.refine)
        if "length" in case.params and mode == "cycle":
            groups = [rail_hole_name(i) for i in range(len(_layout(case.params["length"]).hole_x))]
            refine = tuple(dict.fromkeys(refine + tuple(groups)))
        loads = [UnitLoad("bearing", g, d) for g in groups for d in (ncyc if mode == "cycle" else norig)]
        loads += [u for u in case.loads if u.kind == "inertia"]
        if mode == "original" and "length" not in case.params:  # a fitting's fixed study load stays exact
            loads += list(case.loads)
        key = _case_key(case)
        old_case, old_loads = specs.get(key, (case, []))
        specs[key] = (dataclasses.replace(old_case, name="basis",
                                          refine=tuple(sorted(set(old_case.refine) | set(refine)))),
                      list(dict.fromkeys(old_loads + loads)))
    return specs


def build_bases(p: SweepParams, solver: str = "auto") -> dict[tuple, UnitBasis]:
    """One mesh, one factorisation and the unit solutions of every part geometry and support set."""
    from rigfem.fe.cache import cached_solve
    from rigfem.fe.model import build_model
    from rigfem.fe.partcase import fe_load, mesh_case, relieved_cases, supports_of
    from rigfem.fe.supports import FreeBody
    from rigfem.fe.tensors import von_mises

    s = p.settings()
    out = {}
    models: dict[tuple, tuple] = {}
    specs = _basis_specs(p, s)
    for key, (case, loads) in specs.items():
        geo = key[:2]
        refine = tuple(sorted({g for k2, (c, _) in specs.items() if k2[:2] == geo for g in c.refine}))
        if geo not in models:
            pm = mesh_case(dataclasses.replace(case, refine=refine), s.size_mm, s.local_size_mm)
            models[geo] = (pm, build_model(pm, s.material, s.order))
        pm, model = models[geo]
        supports = supports_of(case)
        fe_loads = [fe_load(u) for u in loads]
        if any(isinstance(x, FreeBody) for x in supports):
            fe_loads = relieved_cases(model, fe_loads)[0]
        sol = cached_solve(model, supports, fe_loads, solver=solver)
        out[key] = _reduce(key, loads, sol.nodal_stress, von_mises(sol.nodal_stress),
                           model.volume * s.material.density * 1e3)
    return out


def _reduce(key: tuple, loads: list[UnitLoad], S: np.ndarray, vm: np.ndarray, fe_mass: float) -> UnitBasis:
    """Index the unit loads and keep float32 fields and each field's top nodes."""
    groups: dict[str, list] = {}
    inertia = {}
    for j, u in enumerate(loads):
        if u.kind == "bearing":
            groups.setdefault(u.group, []).append((np.mod(np.arctan2(u.direction[1], u.direction[0]), 2 * np.pi), j))
        else:
            inertia[(u.component, tuple(u.direction))] = j
    g = {}
    for name, lst in groups.items():
        lst.sort()
        g[name] = (np.array([a for a, _ in lst]), np.array([j for _, j in lst]))
    n_top = min(TOP_NODES, vm.shape[1])
    top = np.argpartition(-vm, n_top - 1, axis=1)[:, :n_top]
    return UnitBasis(key, loads, g, inertia, S.astype(np.float32), vm.astype(np.float32), top, fe_mass)


def _columns(b: UnitBasis, u: UnitLoad, mass_ratio: float) -> list[tuple[int, float]]:
    """Basis columns and weights that reproduce unit load ``u`` (direction split if needed)."""
    if u.kind == "inertia":
        return [(b.inertia[(u.component, tuple(u.direction))], mass_ratio)]
    ang, cols = b.groups[u.group]
    a = np.mod(np.arctan2(u.direction[1], u.direction[0]), 2 * np.pi)
    diff = np.abs((ang - a + np.pi) % (2 * np.pi) - np.pi)
    i = int(np.argmin(diff))
    if diff[i] < 1e-9:
        return [(int(cols[i]), 1.0)]
    lo = int(np.searchsorted(ang, a)) - 1
    i0, i1 = lo % len(ang), (lo + 1) % len(ang)
    e0, e1 = np.array([np.cos(ang[i0]), np.sin(ang[i0])]), np.array([np.cos(ang[i1]), np.sin(ang[i1])])
    w = np.linalg.solve(np.c_[e0, e1], [np.cos(a), np.sin(a)])
    if (w < -1e-12).any() or (diff[i0] + diff[i1]) > np.pi / 2 + 1e-9:
        raise InputError(f"bearing direction on {u.group} is not between two basis directions")
    return [(int(cols[i0]), float(w[0])), (int(cols[i1]), float(w[1]))]


def _row_peaks(C: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Peak von Mises of every row of coefficients C (n, k) over the nodes of S (k, P, 6)."""
    from rigfem.fe.tensors import von_mises

    return np.concatenate([von_mises(np.tensordot(C[s:s + ROW_CHUNK], S, 1)).max(axis=1)
                           for s in range(0, len(C), ROW_CHUNK)])


def case_peak(b: UnitBasis, case: PartCase, exact: bool = False) -> tuple[float, float]:
    """Peak von Mises (MPa) of a case over all rows, and its crank angle (deg): exact, by bounds.

    Von Mises is a norm of the stress deviator, so at node p and any row of coefficients c,
    vm(Σ c_k σ_k) ≤ Σ |c_k| vm(σ_k).  The rows are split into :data:`BOUND_GROUPS` groups,
    each bounded per node with its largest |c_k|; the combination is evaluated at the
    :data:`TOP_NODES` highest nodes of every unit field it uses (a lower bound of the peak),
    then only at the nodes whose bound reaches that lower bound, group by group.  No node that
    can hold the peak is skipped; ``exact=True`` evaluates every node (the tests' reference).
    """
    M = np.zeros((len(case.loads), len(b.loads)))
    for i, u in enumerate(case.loads):
        ratio = case.mass_kg / b.fe_mass if (u.kind == "inertia" and case.mass_kg) else 1.0
        for j, w in _columns(b, u, ratio):
            M[i, j] += w
    C = case.coef @ M
    used = np.flatnonzero(np.abs(C).max(axis=0) > 0)
    if used.size == 0:
        return 0.0, float(case.rows[0])
    rows_peak = superposed_peaks(b, C[:, used].astype(np.float32), used, exact)
    r = int(np.argmax(rows_peak))
    return float(rows_peak[r]), float(case.rows[r])


def superposed_peaks(b: UnitBasis, C: np.ndarray, used: np.ndarray, exact: bool = False) -> np.ndarray:
    """Peak von Mises of each row of ``C`` (rows, len(used)) over the basis fields ``used``;
    with bounds (see :func:`case_peak`) only the largest row's value is guaranteed exact."""
    if exact:
        return _row_peaks(C, b.S[used])
    cand = np.unique(b.top[used])
    rows_peak = _row_peaks(C, b.S[np.ix_(used, cand)])
    floor = rows_peak.max() * (1 - 1e-4)  # float32 round-off margin
    edges = np.linspace(0, len(C), min(BOUND_GROUPS, len(C)) + 1).astype(int)
    cmax = np.stack([np.abs(C[a:e]).max(axis=0) for a, e in zip(edges[:-1], edges[1:])])
    bound = cmax @ b.vm[used]  # (groups, N)
    for g, (a, e) in enumerate(zip(edges[:-1], edges[1:])):
        more = np.setdiff1d(np.flatnonzero(bound[g] >= floor), cand, assume_unique=True)
        if more.size:
            rows_peak[a:e] = np.maximum(rows_peak[a:e], _row_peaks(C[a:e], b.S[np.ix_(used, more)]))
    return rows_peak


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
    from rigfem.dynamics.linkage import AssemblyError, ClosureError

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
        peak, deg = case_peak(bases[_case_key(case)], case)
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
              progress: bool = True, bases: dict | None = None, solver: str = "auto"):
    """Run (or resume) a sweep; return the table (pandas DataFrame, one row per configuration).

    ``work_dir``: where finished chunks are stored (a folder per parameter hash is made in it).
    ``distributed``: run chunks on Dask (default: when ``workers > 1`` or a ``scheduler`` is
    given); ``scheduler`` is ``tcp://HOST:PORT`` of an existing cluster, else a LocalCluster
    with ``workers`` processes runs inside this process.  ``configs``: only these configurations
    (default: every mountable one).  ``bases``: unit solutions already built for ``p``.
    """

    import pandas as pd
    from tqdm import tqdm

    from rigfem.mesh.cache import read_entry

    t0 = time.perf_counter()
    check_range("chunk_size", chunk_size, 1, 100_000)
    check_range("workers", workers, 1, 256)
    configs = enumerate_configs(p) if configs is None else configs
    tag = hashlib.sha256(json.dumps([configs, chunk_size], sort_keys=True).encode()).hexdigest()[:8]
    key = p.key()
    work = Path(work_dir) / f"{key}-{tag}"
    work.mkdir(parents=True, exist_ok=True)
    (Path(work_dir) / ".gitignore").write_text("*\n")  # stored chunks never enter the repository
    (work / "params.json").write_text(json.dumps(dataclasses.asdict(p), indent=1, default=str))
    chunks = [configs[i:i + chunk_size] for i in range(0, len(configs), chunk_size)]
    todo = [i for i in range(len(chunks)) if read_entry(*_chunk(work, key, i, chunks[i])) is None]
    bar = tqdm(total=len(configs), unit="cfg", disable=not progress or None, desc=p.linkage_type,
               initial=sum(len(chunks[i]) for i in range(len(chunks)) if i not in set(todo)))
    with bar:
        if todo:
            if bases is None:
                bar.set_postfix_str("unit solutions")
                bases = build_bases(p, solver)
                bar.set_postfix_str("")
            if distributed is None:
                distributed = workers > 1 or scheduler is not None
            if distributed:
                _run_dask(chunks, todo, p, bases, work, key, workers, scheduler, bar)
            else:
                for i in todo:
                    _write_chunk(work, key, i, chunks[i], run_chunk(chunks[i], p, bases))
                    bar.update(len(chunks[i]))
    timing = work / "timing.json"
    spent = json.loads(timing.read_text())["seconds"] if timing.is_file() else 0.0
    if todo:  # compute time over every run that computed chunks of this sweep
        spent += time.perf_counter() - t0
        timing.write_text(json.dumps({"seconds": spent}))
    table = pd.concat([pd.read_csv(_chunk(work, key, i, chunks[i])[0] / "rows.csv", keep_default_na=False,
                                   na_values=[""])
                       for i in range(len(chunks))], ignore_index=True)
    table = table[_column_order(list(table.columns), p)]
    table.attrs["compute_seconds"] = spent or None
    return table


class _Mapped(np.memmap):
    """A read-only memory-mapped array that pickles as its file name: the workers of a local
    cluster map the same file (one copy in the page cache) instead of each receiving a copy."""

    def __reduce__(self):
        return _open_mapped, (self.filename,)


def _open_mapped(path: str) -> np.ndarray:
    return np.load(path, mmap_mode="r")


def _map_bases(bases: dict[tuple, UnitBasis], folder: Path) -> dict[tuple, UnitBasis]:
    """``bases`` with their stress fields stored in ``folder`` and memory-mapped from there."""
    out = {}
    for i, (key, b) in enumerate(bases.items()):
        arrays = {}
        for name in ("S", "vm"):
            f = folder / f"basis{i}_{name}.npy"
            np.save(f, getattr(b, name))
            arrays[name] = np.load(f, mmap_mode="r").view(_Mapped)
        out[key] = dataclasses.replace(b, **arrays)
    return out


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
    with maps as folder, local as cluster, Client(scheduler or cluster) as client:  # the client closes first
        if folder is not None:  # same machine: the workers map one copy of the unit fields
            bases = _map_bases(bases, Path(folder))
        [shared] = client.scatter([bases], broadcast=True)  # unit solutions shipped once per worker
        futures = {client.submit(run_chunk, chunks[i], p, shared, pure=False): i for i in todo}
        for fut in as_completed(futures):
            i = futures.pop(fut)
            _write_chunk(work, key, i, chunks[i], fut.result())
            bar.update(len(chunks[i]))
