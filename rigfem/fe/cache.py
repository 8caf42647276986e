"""Unit solutions cached on disk: solve a part model once, load it in every later check.

Linear elasticity is linear: a part's mesh, material, element order, supports and unit loads
decide its solution completely, whatever the configuration that asked for it.  A check that
needs the same part model again loads the stored arrays (displacements, loads, reactions,
recovered stresses) instead of assembling, factorising and solving; the stored arrays are the
solver's own float64 results, so a warm run reproduces a cold one exactly.  Entries are
verified cache entries (:mod:`rigfem.cache`, kind ``solutions``); a loaded solution must also
pass :func:`check_energy`, an invariant no stored file can fake: a non-zero load does positive work.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np

from rigfem.cache import Cache, Entry, array_digest, resolve, save_arrays
from rigfem.errors import ComputeError
from rigfem.fe.solution import Solution
from rigfem.tensors import von_mises

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
    """Everything that shapes the solution (the entry's key), or None for a mesh without a key."""
    mesh_key = model.part.meta.get("hash")
    if not mesh_key:
        return None
    return {"mesh": mesh_key, "order": model.mesh.order, "material": _plain(model.material),
            "supports": _plain(supports), "cases": _plain(cases), "solver": solver, "rtol": rtol}


def _key(inputs: dict) -> str:
    """A solution's identity (a peak sweep of it is keyed by it)."""
    return hashlib.sha256(json.dumps(inputs, sort_keys=True, default=str).encode()).hexdigest()[:32]


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


def peak_sweep(sol: Solution, C: np.ndarray, cache: Cache) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`Solution.peak_sweep` of a cached solution through ``cache``: the peak von Mises (n,)
    and its node (n,) of every row of C (n, k).  A stored sweep is used only if every stored peak
    is the von Mises stress of the combination at the stored node (recomputed here)."""
    if not sol.key:
        return sol.peak_sweep(C)
    C = np.atleast_2d(np.asarray(C, dtype=float))

    def at_nodes(a: tuple) -> str:
        vals, nodes = a
        at = von_mises(np.einsum("rk,krc->rc", C, sol.nodal_stress[:, nodes])) if len(C) else vals
        ok = vals.shape == (len(C),) and np.allclose(at, vals, rtol=1e-9, atol=0.0)
        return "" if ok else "a stored peak is not the stress at its node"

    got, _ = cache.cached("sweeps", {"solution": sol.key, "C": C}, lambda: sol.peak_sweep(C),
                          lambda a, tmp: save_arrays(tmp, {"peak": a[0], "node": a[1]}),
                          lambda entry: (entry.array("peak"), entry.array("node")), at_nodes)
    return got


def _load_solution(model, entry: Entry) -> Solution:
    info = entry.json("info.json")
    dofs = {k: entry.array(f"support_{k}") for k in info["supports"]}
    return Solution(model=model, support_dofs=dofs, method=info["method"], free_body=info["free_body"],
                    times={**info["times"], "cache": 1.0}, key=info["key"], **{k: entry.array(k) for k in _ARRAYS})


def _save_solution(sol: Solution, tmp) -> None:
    save_arrays(tmp, {k: getattr(sol, k) for k in _ARRAYS})
    save_arrays(tmp, {f"support_{k}": v for k, v in sol.support_dofs.items()})
    (tmp / "info.json").write_text(json.dumps({"method": sol.method, "free_body": sol.free_body, "times": sol.times,
                                               "key": sol.key, "supports": list(sol.support_dofs)}))


def _check_solution(model, sol: Solution) -> str:
    return ("another mesh size" if sol.U.shape[0] != model.mesh.ndof else "") or check_energy(sol)


def ladder_inputs(group: list[tuple[str, object]], levels: list[tuple[str, object]], solver: str) -> dict:
    """Everything that decides where a part geometry's mesh ladder stops: its (mode, case) pairs
    (arrays by digest), every level's settings and the solver (the package's code, which holds the
    mesher, the solver and the verdict layer's judge, is in every key)."""
    def case(mode: str, c) -> dict:
        return {"mode": mode, **{f.name: array_digest(v) if isinstance(v, np.ndarray) else _plain(v)
                                 for f in dataclasses.fields(c) for v in [getattr(c, f.name)]}}
    return {"cases": [case(m, c) for m, c in group], "levels": [[n, _plain(s)] for n, s in levels],
            "solver": solver}


def read_ladder(inputs: dict, cache: Cache) -> list[dict] | None:
    """The levels a ladder solved before (:func:`save_ladder`; the last is where it stopped), or None."""
    names = [n for n, _ in inputs["levels"]]

    def check(ladder: list) -> str:
        at = [names.index(s["level"]) if s["level"] in names else -1 for s in ladder]
        # the ladder's levels in its order, each at most once (a level predicted unsettled is skipped)
        ok = bool(at) and min(at) >= 0 and all(a < b for a, b in zip(at, at[1:]))
        return "" if ok else "its levels are not the ladder's"

    return cache.get("ladders", inputs, lambda entry: entry.json("ladder.json"), check)


def save_ladder(inputs: dict, ladder: list[dict], cache: Cache) -> None:
    """Store the levels a ladder climbed (the last is where it stopped) and what each cost, so a
    warm check loads that level's solution only, not the coarser ones it discarded."""
    cache.put("ladders", inputs, lambda tmp: (tmp / "ladder.json").write_text(json.dumps(ladder)))


def cached_solve(model, supports: list, cases: list, solver: str = "auto", rtol: float = 1e-10,
                 cache: Cache | None = None) -> Solution:
    """:func:`rigfem.fe.model.solve`, through ``cache`` (None: the environment's) when the model's
    mesh has a key."""
    from rigfem.fe.model import solve

    cache = resolve(cache)
    inputs = solution_inputs(model, supports, cases, solver, rtol)
    if inputs is not None:
        sol = cache.get("solutions", inputs, lambda entry: _load_solution(model, entry),
                        lambda s: _check_solution(model, s))
        if sol is not None:
            return sol
    sol = solve(model, supports, cases, solver=solver, rtol=rtol)
    why = check_energy(sol)
    if why:
        raise ComputeError(f"the solution of part {model.part.name} cannot be right: {why}")
    if inputs is not None:
        sol.key = _key(inputs)
        cache.put("solutions", inputs, lambda tmp: _save_solution(sol, tmp))
    return sol
