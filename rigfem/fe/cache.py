"""Unit solutions cached on disk: solve a part model once, load it in every later check.

Linear elasticity is linear: a part's mesh, material, element order, supports and unit loads
decide its solution completely, whatever the configuration that asked for it.  A check (or a
configuration of the sweep) that needs the same part model again loads the stored arrays
(displacements, loads, reactions, recovered stresses) instead of assembling, factorising and
solving; the stored arrays are the solver's own float64 results, so a warm run reproduces a
cold one exactly.  Entries live under ``$RIGFEM_CACHE/solutions`` (default
``~/.cache/rigfem``), one folder per key; delete the folder to reclaim the space.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from rigfem import __version__
from rigfem.fe.solution import Solution

#: bump when what a solution holds, or how it is computed, changes
SOLUTION_RECIPE = 1
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


@functools.lru_cache(maxsize=1)
def _code_hash() -> str:
    """Hash of the source that computes a solution (meshing, FE), so an edit invalidates entries."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    shaping = ("assembly", "forces", "supports", "solver", "model", "stress")
    for f in sorted([*(root / "fe" / f"{m}.py" for m in shaping), *root.glob("mesh/*.py"), root / "material.py"]):
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def solution_key(model, supports: list, cases: list, solver: str, rtol: float) -> str | None:
    """Hash of everything that shapes the solution, or None for a mesh without a cache key."""
    mesh_key = model.part.meta.get("hash")
    if not mesh_key:
        return None
    src = {"mesh": mesh_key, "order": model.mesh.order, "material": _plain(model.material),
           "supports": _plain(supports), "cases": _plain(cases), "solver": solver, "rtol": rtol,
           "recipe": SOLUTION_RECIPE, "rigfem": __version__, "code": _code_hash()}
    return hashlib.sha256(json.dumps(src, sort_keys=True, default=str).encode()).hexdigest()[:32]


def _folder(key: str) -> Path:
    from rigfem.mesh.mesher import cache_dir

    return cache_dir() / "solutions" / key


def load_solution(model, key: str) -> Solution | None:
    """The cached solution of ``key`` for ``model``, or None (missing or unreadable entry)."""
    d = _folder(key)
    try:
        info = json.loads((d / "info.json").read_text())
        arrays = {k: np.load(d / f"{k}.npy") for k in _ARRAYS}
        dofs = np.load(d / "support_dofs.npz")
    except (OSError, ValueError, KeyError):
        return None
    if arrays["U"].shape[0] != model.mesh.ndof:
        return None
    return Solution(model=model, support_dofs={k: dofs[k] for k in dofs.files}, method=info["method"],
                    free_body=info["free_body"], times={**info["times"], "cache": 1.0}, **arrays)


def save_solution(sol: Solution, key: str) -> None:
    """Store ``sol`` under ``key``: written to a temporary folder, then renamed into place."""
    d = _folder(key)
    if d.exists():
        return
    d.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{key}-", dir=d.parent))
    try:
        for k in _ARRAYS:
            np.save(tmp / f"{k}.npy", getattr(sol, k))
        np.savez(tmp / "support_dofs.npz", **sol.support_dofs)
        (tmp / "info.json").write_text(json.dumps({"method": sol.method, "free_body": sol.free_body,
                                                   "times": sol.times}))
        os.replace(tmp, d)
    except OSError:  # a full disk or a concurrent writer: the cache is an optimisation only
        shutil.rmtree(tmp, ignore_errors=True)


def cached_solve(model, supports: list, cases: list, solver: str = "auto", rtol: float = 1e-10,
                 use_cache: bool = True) -> Solution:
    """:func:`rigfem.fe.model.solve`, through the disk cache when the model's mesh has a key."""
    from rigfem.fe.model import solve

    key = solution_key(model, supports, cases, solver, rtol) if use_cache else None
    if key is not None:
        sol = load_solution(model, key)
        if sol is not None:
            return sol
    sol = solve(model, supports, cases, solver=solver, rtol=rtol)
    if key is not None:
        save_solution(sol, key)
    return sol
