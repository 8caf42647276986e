"""Cross-check against CalculiX: re-solve each part case in ccx on the identical model and compare."""

from __future__ import annotations

import dataclasses
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rigfem.errors import InputError
from rigfem.tensors import von_mises
from rigfem.io.calculix import CcxResult, export_model, run_ccx

if TYPE_CHECKING:
    from rigfem.context import Context
    from rigfem.job import Job


@dataclass
class Comparison:
    """rigfem against CalculiX for one load case (same model)."""

    peak_von_mises: float  #: MPa, rigfem's peak nodal von Mises
    peak_von_mises_ccx: float  #: MPa
    peak_rel_diff: float  #: ccx / rigfem − 1
    max_displacement: float  #: mm, rigfem's largest nodal displacement magnitude
    max_displacement_ccx: float  #: mm
    displacement_rel_diff: float  #: max over nodes |u_ccx − u_rigfem| / max |u_rigfem|


def compare(solution: Any, result: CcxResult, coef: np.ndarray | None = None) -> list[Comparison]:
    """Per load case differences between a rigfem :class:`~rigfem.fe.solution.Solution` and ccx.

    ccx's case j is compared with the combination ``coef[j]`` of the solution's cases
    (default: case j itself).  For a free body the rigid motion is removed from ccx's
    displacement as rigfem does.
    """
    from rigfem.fe.supports import rigid_modes

    x = solution.model.mesh.nodes
    n, k = len(x), solution.cases
    coef = np.eye(k) if coef is None else np.atleast_2d(np.asarray(coef, dtype=float))
    if result.displacement.shape[0] != len(coef):
        raise InputError(f"ccx result has {result.displacement.shape[0]} load cases, expected {len(coef)}")
    out = []
    for j, c in enumerate(coef):
        u_fe, u_cx = solution.displacement(c), result.displacement[j, :n]
        if solution.free_body:
            R = rigid_modes(x)
            v = u_cx.ravel()
            u_cx = (v - R @ np.linalg.lstsq(R, v, rcond=None)[0]).reshape(-1, 3)
        vm_fe, vm_cx = solution.von_mises(c).max(), von_mises(result.stress[j, :n]).max()
        d_fe, d_cx = np.linalg.norm(u_fe, axis=1).max(), np.linalg.norm(u_cx, axis=1).max()
        du = np.linalg.norm(u_cx - u_fe, axis=1).max()
        out.append(Comparison(float(vm_fe), float(vm_cx), _rel(vm_cx - vm_fe, vm_fe), float(d_fe), float(d_cx),
                              _rel(du, d_fe)))
    return out


def _rel(diff: float, ref: float) -> float:
    """diff / ref; 0 when both are 0 (an unloaded case), inf when only ref is."""
    return float(diff / ref) if ref != 0 else (0.0 if diff == 0 else float("inf"))


def cross_check(model: Any, supports: list, cases: list | None = None, solution: Any = None,
                coef: np.ndarray | None = None, threads: int = 1,
                workdir: str | os.PathLike | None = None) -> list[Comparison]:
    """Solve in rigfem (unless ``solution`` is given) and in ccx; compare case by case.

    With ``solution`` and ``coef`` (m, k) — e.g. the critical crank angle of ``rigfem check``,
    ``coef = case_result.coef[[row]]`` — ccx solves the m load combinations
    ``solution.loads(c)`` (c a row of ``coef``) instead of ``cases``.
    """
    if solution is None:
        from rigfem.fe.model import solve

        solution = solve(model, supports, cases)
    loads = cases if coef is None else np.column_stack([solution.loads(c) for c in np.atleast_2d(coef)])
    with tempfile.TemporaryDirectory(prefix="rigfem-inp-") as tmp:
        deck = export_model(model, supports, loads, Path(workdir or tmp) / "model.inp")
        return compare(solution, run_ccx(deck, threads=threads, workdir=workdir), coef)


def verify_job(job: Job, threads: int = 1, ctx: Context | None = None) -> list[dict]:
    """``rigfem check``'s part cases of a read job (:func:`rigfem.job.read_job`: the scene is
    validated by the caller, before ccx is looked for), each critical load combination re-solved
    by ccx on the same model.  One entry per part case: name, mode, DOF and the :class:`Comparison`
    fields; a linkage at a toggle has none.  Raises :class:`CalculixError` when ccx is missing."""
    from rigfem.context import default_context
    from rigfem.fe.partcase import supports_of
    from rigfem.pipeline import solve_job

    ctx = default_context(ctx)
    out = []
    for r in solve_job(job, ctx).results:
        ctx.observer.stage(f"CalculiX part {r.case.name} ({r.mode})")
        (c,) = cross_check(r.solution.model, supports_of(r.case), solution=r.solution, coef=r.coef[[r.row]],
                           threads=threads)
        out.append({"part": r.case.name, "mode": r.mode, "dof": int(r.solution.model.mesh.ndof),
                    **dataclasses.asdict(c)})
    return out
