"""Unit solutions cached on disk: solve a part model once, load it in every later check.

Linear elasticity is linear: a part's mesh, material, element order, supports and unit loads
decide its solution completely, whatever the configuration that asked for it.  A check (or a
configuration of the sweep) that needs the same part model again loads the stored arrays
(displacements, loads, reactions, recovered stresses) instead of assembling, factorising and
solving; the stored arrays are the solver's own float64 results, so a warm run reproduces a
cold one exactly.  Entries are verified cache entries (:mod:`rigfem.mesh.cache`) under
``$RIGFEM_CACHE/solutions``; a loaded solution must also pass :func:`check_energy`, an
invariant no stored file can fake: a non-zero load does positive work.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from pathlib import Path

import numpy as np

from rigfem.errors import ComputeError
from rigfem.fe.solution import Solution
from rigfem.fe.tensors import von_mises
from rigfem.mesh.cache import (
    array_digest,
    cache_dir,
    cached_arrays,
    code_hash,
    discard,
    entry_key,
    read_arrays,
    read_entry,
    save_arrays,
    write_entry,
)
from rigfem.mesh.mesher import MESH_CODE

#: the source files that compute a solution (with the mesh's): an edit invalidates the entries
SOLUTION_CODE = (*MESH_CODE, "material.py", "fe/assembly.py", "fe/forces.py", "fe/supports.py", "fe/solver.py",
                 "fe/kernels.py", "fe/model.py", "fe/stress.py", "fe/solution.py", "fe/cache.py")
_ARRAYS = ("F", "U", "reactions", "nodal_stress", "residuals", "backward_errors")


def _plain(obj):
    if dataclasses.is_dataclass(obj):
        return {"type": type(obj).__name__, **{k: _plain(v) for k, v in dataclasses.asdict(obj).items()}}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def solution_inputs(model, supports: list, cases: list, solver: str, rtol: float) -> dict | None:
    """Everything that shapes the solution (the entry's key), or None for a mesh without a cache key."""
    mesh_key = model.part.meta.get("hash")
    if not mesh_key:
        return None
    return {"mesh": mesh_key, "order": model.mesh.order, "material": _plain(model.material),
            "supports": _plain(supports), "cases": _plain(cases), "solver": solver, "rtol": rtol,
            "code": code_hash(*SOLUTION_CODE)}


def _folder(inputs: dict) -> Path:
    return cache_dir() / "solutions" / entry_key(inputs)


def check_energy(sol: Solution) -> str:
    """Why ``sol`` cannot be right ("" if it can): every array finite, and every load column
    with a force on an unsupported DOF storing positive strain energy ``U·(F + reactions) = UᵀKU``."""
    # a NaN or an infinity anywhere makes the sum non-finite (one pass, no mask the size of the array)
    bad = [k for k in _ARRAYS if not np.isfinite(np.sum(getattr(sol, k)))]
    if bad:
        return f"non-finite values in {', '.join(bad)}"
    held = np.unique(np.concatenate([np.ravel(d) for d in sol.support_dofs.values()] or [np.zeros(0, int)]))
    F = np.abs(sol.F)
    F[held.astype(np.int64)] = 0.0  # the loads on unsupported DOFs
    peak = F.max(axis=0, initial=0.0)
    loaded = peak > 1e-12 * peak.max(initial=0.0)  # not a column of round-off (a relieved self-balance)
    energy = np.einsum("ik,ik->k", sol.U, sol.F) + np.einsum("ik,ik->k", sol.U, sol.reactions)
    zero = np.flatnonzero(loaded & ~(energy > 0))
    return f"load case(s) {zero.tolist()} carry load but store no strain energy" if zero.size else ""


def peak_sweep(sol: Solution, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`Solution.peak_sweep` of a cached solution through the cache: the peak von Mises (n,)
    and its node (n,) of every row of C (n, k).  A stored sweep is used only if every stored peak
    is the von Mises stress of the combination at the stored node (recomputed here)."""
    if not sol.key:
        return sol.peak_sweep(C)
    C = np.atleast_2d(np.asarray(C, dtype=float))
    inputs = {"solution": sol.key, "C": array_digest(C), "code": code_hash(*SOLUTION_CODE, "fe/tensors.py")}

    def at_nodes(a: dict) -> str:
        vals, nodes = a["peak"], a["node"]
        at = von_mises(np.einsum("rk,krc->rc", C, sol.nodal_stress[:, nodes])) if len(C) else vals
        ok = vals.shape == (len(C),) and np.allclose(at, vals, rtol=1e-9, atol=0.0)
        return "" if ok else "a stored peak is not the stress at its node"

    got, _ = cached_arrays("sweeps", inputs, ("peak", "node"),
                           lambda: dict(zip(("peak", "node"), sol.peak_sweep(C))), at_nodes)
    return got["peak"], got["node"]


def load_solution(model, inputs: dict) -> Solution | None:
    """The cached solution of ``inputs`` for ``model``, or None (missing, or a bad entry: discarded)."""
    d = _folder(inputs)
    arrays = read_arrays(d, inputs, _ARRAYS)
    if arrays is None:
        return None
    try:
        info = json.loads((d / "info.json").read_text())
        with np.load(d / "support_dofs.npz", allow_pickle=False) as z:
            dofs = {k: z[k] for k in z.files}
        sol = Solution(model=model, support_dofs=dofs, method=info["method"], free_body=info["free_body"],
                       times={**info["times"], "cache": 1.0}, key=d.name, **arrays)
        why = "" if sol.U.shape[0] == model.mesh.ndof else "another mesh size"
        why = why or check_energy(sol)
    except (OSError, ValueError, KeyError, TypeError) as e:
        why = f"unreadable: {type(e).__name__}"
    if why:
        return discard(d, why)
    return sol


def save_solution(sol: Solution, inputs: dict) -> None:
    """Store ``sol`` as a verified entry of ``inputs`` (see :mod:`rigfem.mesh.cache`)."""
    def write(tmp: Path) -> None:
        save_arrays(tmp, {k: getattr(sol, k) for k in _ARRAYS})
        np.savez(tmp / "support_dofs.npz", **sol.support_dofs)
        (tmp / "info.json").write_text(json.dumps({"method": sol.method, "free_body": sol.free_body,
                                                   "times": sol.times}))
    write_entry(_folder(inputs), inputs, write)


def ladder_inputs(group: list[tuple[str, object]], levels: list[tuple[str, object]], solver: str) -> dict:
    """Everything that decides where a part geometry's mesh ladder stops: its (mode, case) pairs
    (arrays by digest), every level's settings, the solver, and the code of the whole package
    (the mesh, the solution and the verdict layer's judge all take part)."""
    def case(mode: str, c) -> dict:
        return {"mode": mode, **{f.name: array_digest(v) if isinstance(v, np.ndarray) else _plain(v)
                                 for f in dataclasses.fields(c) for v in [getattr(c, f.name)]}}
    return {"cases": [case(m, c) for m, c in group], "levels": [[n, _plain(s)] for n, s in levels],
            "solver": solver, "code": _package_code()}


@functools.lru_cache(maxsize=1)
def _package_code() -> str:
    return code_hash("**/*.py")


def read_ladder(inputs: dict) -> list[dict] | None:
    """The levels a ladder solved before (:func:`save_ladder`; the last is where it stopped), or
    None (missing, or bad: discarded)."""
    d = read_entry(_ladder_folder(inputs), inputs)
    if d is None:
        return None
    try:
        ladder = json.loads((d / "ladder.json").read_text())
        names = [n for n, _ in inputs["levels"]]
        at = [names.index(s["level"]) if s["level"] in names else -1 for s in ladder]
    except (OSError, ValueError, KeyError, TypeError) as e:
        return discard(d, f"unreadable: {type(e).__name__}")
    # the ladder's levels in its order, each at most once (a level predicted unsettled is skipped)
    ok = bool(at) and min(at) >= 0 and all(a < b for a, b in zip(at, at[1:]))
    return ladder if ok else discard(d, "its levels are not the ladder's")


def save_ladder(inputs: dict, ladder: list[dict]) -> None:
    """Store the levels a ladder climbed (the last is where it stopped) and what each cost, so a
    warm check loads that level's solution only, not the coarser ones it discarded."""
    write_entry(_ladder_folder(inputs), inputs, lambda tmp: (tmp / "ladder.json").write_text(json.dumps(ladder)))


def _ladder_folder(inputs: dict) -> Path:
    return cache_dir() / "ladders" / entry_key(inputs)


def cached_solve(model, supports: list, cases: list, solver: str = "auto", rtol: float = 1e-10,
                 use_cache: bool = True, factorised: dict | None = None, store=None) -> Solution:
    """:func:`rigfem.fe.model.solve`, through the disk cache when the model's mesh has a key.

    ``factorised`` (a dict the caller keeps): a miss is solved with the factorisation kept there
    for this model and supports, made and kept there at the first miss; a caller solving one
    model's cases in batches factorises once, and frees the factors by dropping the dict.
    ``store(write)`` runs a new entry's ``write()`` (default: here, now); a caller may run it in
    another thread while it solves the next batch."""
    from rigfem.fe.model import StaticProblem, solve

    inputs = solution_inputs(model, supports, cases, solver, rtol) if use_cache else None
    if inputs is not None:
        sol = load_solution(model, inputs)
        if sol is not None:
            return sol
    if factorised is None:
        sol = solve(model, supports, cases, solver=solver, rtol=rtol)
    else:
        key = (id(model), json.dumps(_plain(supports)), solver, rtol)
        if key not in factorised:
            factorised[key] = StaticProblem(model, supports, solver, rtol)
        sol = factorised[key].solve(cases)
    why = check_energy(sol)
    if why:
        raise ComputeError(f"the solution of part {model.part.name} cannot be right: {why}")
    if inputs is not None:
        (store or (lambda write: write()))(lambda: save_solution(sol, inputs))
        sol.key = _folder(inputs).name
    return sol
