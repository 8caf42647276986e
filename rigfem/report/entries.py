"""A checked part case as the report shows it: its verdict with the mesh, the solve and the caveats behind it.

Plain data (MPa, mm, deg, N, N·mm) for ``report.json``; the Markdown and HTML pages render it.
"""

from __future__ import annotations

import numpy as np

from rigfem.fe.model import LOCKING_NU
from rigfem.fe.partcase import CaseResult
from rigfem.rig.parts import load_part
from rigfem.verdict.criterion import IMBALANCE_TOL
from rigfem.verdict.part import PartVerdict

__all__ = ["P1_NOTE", "ELEMENT", "balance", "loads_and_fixtures", "part_entry"]

#: what a P1 (linear tetrahedron) report says: a known under-predictor of bending stress
P1_NOTE = ("linear tetrahedra (order 1) under-predict bending stress: on the standard mesh they read the reference "
           "parts' peaks 12-29 % low (results/convergence/summary.md); the error band uses the P1 factor on the "
           "ZZ estimate (results/convergence/band_coverage.md); use order 2 for a verdict")

#: element type and order, as the mesh table names it
ELEMENT = {1: "tetrahedron, 4-node linear (C3D4)", 2: "tetrahedron, 10-node quadratic (C3D10)"}


def _profile_caveat(res: CaseResult) -> list[str]:
    """A rail whose section is heavier than the catalogue's is stiffer and stronger than the real one."""
    part = load_part(res.case.part, res.case.params or None)
    ref = part.reference.get("linear_mass_catalogue")
    if part.kind != "rail" or ref is None:
        return []
    kg_m = res.solution.model.volume * part.density * 1e-9 / (part["length"] / 1000.0)
    if kg_m <= 1.05 * ref.value:
        return []
    return [f"rail section {kg_m:.2f} kg/m against the catalogue's {ref.value:g} kg/m: the modelled profile "
            f"is stiffer and stronger than the real one, so this stress is likely low (a 3.1 kg/m profile "
            f"carried 1.8-2.1x the rectangle's peak: results/rail_profile/study.md)"]


def _size_at(fm, node: int) -> float:
    """Mean edge length (mm) of the elements around ``node``: the mesh size where the peak is."""
    t = fm.elements[(fm.elements == node).any(1), :4]
    x = fm.nodes[t]
    edges = [x[:, i] - x[:, j] for i, j in ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))]
    return float(np.mean(np.linalg.norm(np.stack(edges), axis=-1)))


def balance(sol, c: np.ndarray) -> dict:
    """Free-body balance of the combination ``c``: Σ applied loads (pins and body forces) and Σ support
    reactions, forces (N) and moments about the part frame's origin (N·mm); their sum is ≈ 0."""
    alld = np.arange(len(sol.F))
    app = sol.resultants(alld, sol.loads(c)[:, None])[0]
    reaction = sol.reaction(c)[:, None]
    sup = {n: sol.resultants(d, reaction)[0] for n, d in sol.support_dofs.items()}
    tot_s = np.sum(list(sup.values()), axis=0) if sup else np.zeros(6)
    v3 = lambda v: [float(t) for t in v]  # noqa: E731
    return {"applied_N": v3(app[:3]), "applied_Nmm": v3(app[3:]), "supports_N": v3(tot_s[:3]),
            "supports_Nmm": v3(tot_s[3:]),
            "supports": {n: {"force_N": v3(v[:3]), "moment_Nmm": v3(v[3:])} for n, v in sup.items()},
            "residual_N": float(np.linalg.norm(app[:3] + tot_s[:3])),
            "residual_Nmm": float(np.linalg.norm(app[3:] + tot_s[3:]))}


def _connector(hole: str) -> str:
    """What pushes on a loaded hole: the pin on a plate's bearing seat, a coupling screw otherwise."""
    return "pin on the bearing seat" if hole == "bore" else f"screw in {hole}"


#: what each support of rigfem.fe.supports stands for, by the prefix of its name
_FIXTURE = {"ShaftInHole": "screw: the hole wall on springs (radial stiffness E/r) to a fixed rigid shaft, no preload",
            "Symmetry": "face sliding on its support (zero normal displacement, no friction)",
            "Fixed": "face fixed (all displacements zero)",
            "FreeBody": "free body: inertia relief balances the loads; 3-2-1 point supports carry ≈ 0"}


def loads_and_fixtures(res: CaseResult, bal: dict) -> dict:
    """A part case's loads and fixtures at its critical crank angle (part frame, N): each pin or
    screw force on a hole (cosine bearing pressure on the half it pushes), the body force of the
    part's own inertia (with the inertia relief of a free body), each support's reaction."""
    case, row = res.case, res.row
    holes: dict[str, np.ndarray] = {}
    for u, c in zip(case.loads, case.coef[row]):
        if u.kind == "bearing":
            holes[u.group] = holes.get(u.group, np.zeros(3)) + c * np.asarray(u.direction, float)
    loads = [{"entity": _connector(g), "kind": "bearing load", "force_N": [float(t) for t in f],
              "magnitude_N": float(np.linalg.norm(f))} for g, f in holes.items()]
    body = np.asarray(bal["applied_N"]) - sum(holes.values(), np.zeros(3))
    if any(u.kind == "inertia" for u in case.loads) or res.solution.free_body:
        loads.append({"entity": "the part's own inertia", "kind": "body force (−ρ·a, with inertia relief)",
                      "force_N": [float(t) for t in body], "magnitude_N": float(np.linalg.norm(body))})
    fixtures = [{"entity": name.split("(", 1)[1].rstrip(")") if "(" in name else name,
                 "kind": _FIXTURE.get(name.split("(", 1)[0], name), "reaction_N": v["force_N"],
                 "magnitude_N": float(np.linalg.norm(v["force_N"]))} for name, v in bal["supports"].items()]
    return {"crank_deg": res.crank_deg, "loads": loads, "fixtures": fixtures, "free_body": bool(res.solution.free_body)}


def _fatigue(res: CaseResult, pv: PartVerdict) -> dict | None:
    """The Goodman check, its critical point named by node and place."""
    if pv.fatigue is None:
        return None
    fat = dict(pv.fatigue)
    fat["node"] = int(res.cycle_nodes[fat.pop("point")])
    fat["location_mm"] = [float(v) for v in res.solution.model.mesh.nodes[fat["node"]]]
    return fat


def part_entry(res: CaseResult, pv: PartVerdict, settings) -> dict:
    """Report entry of a case result and its verdict (plain data, MPa, mm, deg)."""
    mat, pk, v = settings.material, res.peak, pv.verdict
    sol = res.solution
    c = res.coef[res.row]
    out = {
        "name": res.case.name, "part": res.case.part, "mode": res.mode,
        "peak_mpa": v.peak_mpa, "crank_deg": res.crank_deg,
        "surface": pk.surface, "location_mm": [round(float(t), 3) + 0.0 for t in pk.xyz],  # + 0.0: never -0.0
        "error_pct": v.error_pct, "limit_mpa": v.limit_mpa, "utilisation_pct": v.utilisation_pct,
        # the band also in MPa and in % of the allowable: ±43.7 % of a peak at 2 % of the allowable is ±0.9 %
        "band_mpa": v.peak_mpa * v.error_pct / 100, "band_pct_of_allowable": v.utilisation_pct * v.error_pct / 100,
        "verdict": v.verdict, "reason": v.reason,
        "max_displacement_mm": float(np.linalg.norm(sol.displacement(c), axis=1).max()),
        "fatigue": _fatigue(res, pv),
        "mesh": {"element": ELEMENT[sol.model.mesh.order],
                 "nodes": int(len(res.mesh.points)), "tets": int(len(res.mesh.tets)),
                 "fe_nodes": int(len(sol.model.mesh.nodes)),
                 "size_at_peak_mm": _size_at(sol.model.mesh, pk.node),
                 "dofs": int(sol.model.mesh.ndof), "order": settings.order,
                 "quality_min": float(res.mesh.quality.get("min", 0.0)),
                 "curved_elements": int(sol.model.mesh.curved.sum()) if sol.model.mesh.curved is not None else 0,
                 "straightened": int(sol.model.mesh.straightened),
                 "cache": res.mesh.meta.get("cache", ""),
                 "asked": settings.asked(), "level": res.level, "stopped": res.stopped, "ladder": list(res.ladder)},
        "solve": {"method": sol.method, "load_cases": int(sol.cases),
                  "rows": int(len(res.case.rows)),
                  "residual_max": float(sol.residuals.max()), "equilibrium_error": float(np.max(sol.equilibrium_error)),
                  "imbalance": {"force_pct": 100 * res.imbalance[0], "moment_pct": 100 * res.imbalance[1],
                                "tolerance_pct": 100 * IMBALANCE_TOL},
                  "seconds": {k: round(t, 3) for k, t in res.seconds.items()}},
        "balance": balance(sol, c),
        "notes": list(res.case.notes),
    }
    out["loads"] = loads_and_fixtures(res, out["balance"])
    if v.reason:
        out["notes"].insert(0, v.reason)
    out["notes"] += _profile_caveat(res)
    if settings.order == 1:
        out["notes"].append(P1_NOTE)
    if settings.order == 1 and mat.nu >= LOCKING_NU:
        out["notes"].append(f"linear elements with nu = {mat.nu:g}: volumetric locking under-predicts stress; "
                            f"use order 2")
    if 1e-3 < max(res.imbalance) <= IMBALANCE_TOL:
        out["notes"].append(f"free-body loads were out of balance by up to {100 * res.imbalance[0]:.1f} % "
                            f"(force), {100 * res.imbalance[1]:.1f} % (moment) (FE vs dynamics mass "
                            f"distribution); removed by inertia relief")
    return out
