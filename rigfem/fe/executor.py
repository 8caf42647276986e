"""The FE stage's executor: which part is meshed and solved when, and what is held in memory.

Every (mode, case) of a check is grouped by part geometry (one mesh and one stiffness each,
:func:`rigfem.fe.partcase.part_geometries`).  Parts are queued smallest first (the estimated
mesh) and their first level's meshes made ahead in the mesher processes (two at a time); the FE
takes the first part in the queue whose mesh is ready.  A part that climbs
(:func:`rigfem.fe.ladder.next_step`) goes to the back of the queue, its next mesh (and the cap's,
in case it climbs on) made while the other parts solve.  A part that is final is reduced to what
a report reads (:func:`rigfem.fe.partcase.finish`) and handed to the sink, and the memory its
solve freed goes back to the system: the unit solutions of the parts already solved are not held
while the next ones are.  Where each part's ladder stopped is stored in the cache, so a later
check of the same cases starts at that level.

What is solved, and how, is the :class:`Plan`'s: tests hand it a fake part solver or judge.
"""

from __future__ import annotations

import collections
import dataclasses
import math
import time
from collections.abc import Callable

from rigfem.cache import Cache
from rigfem.context import Context, default_context
from rigfem.fe.assembly import start_compiling
from rigfem.fe.cache import ladder_inputs, read_ladder, save_ladder
from rigfem.fe.ladder import Judge, next_step
from rigfem.fe.partcase import CaseResult, finish, group_job, part_geometries, solve_group
from rigfem.loads.cases import PartCase
from rigfem.memory import trim_heap
from rigfem.mesh import pool
from rigfem.mesh.mesher import estimate_part, mesh_state, prefetch

__all__ = ["Plan", "Sink", "solve_cases", "next_ready"]

#: how often a part waiting for its mesh looks at the mesher processes, s
POLL_S = 0.05


class Sink:
    """Receives each part's results as the part becomes final (the default keeps them)."""

    def __init__(self) -> None:
        self.results: dict[int, CaseResult] = {}

    def final(self, group: list[tuple[str, PartCase]], results: list[CaseResult]) -> None:
        for (_, case), r in zip(group, results):
            self.results[id(case)] = r


@dataclasses.dataclass(frozen=True)
class Plan:
    """How the FE stage runs: the judge that stops a part's ladder (None: every part at the
    settings' own mesh), the animation frames a final part keeps (None: its whole solution, for
    studies that combine rows no check asked for), and the part solver itself."""

    judge: Judge | None = None
    frames: int | None = 0
    solve: Callable[..., list[CaseResult]] = solve_group


def solve_cases(cases: list[tuple[str, PartCase]], settings, plan: Plan = Plan(),
                ctx: Context | None = None) -> list[CaseResult]:
    """Every (mode, case) solved, in the order given (see the module's docstring); ``ctx`` gives
    the cache, the observer and the solver (default: :func:`rigfem.context.default_context`)."""
    ctx = default_context(ctx)
    cache, observer = ctx.cache, ctx.observer
    geo = part_geometries(cases)
    levels = settings.levels() if plan.judge is not None else [(getattr(settings, "fidelity", ""), settings)]
    ladder = _Ladders(geo, levels, ctx.solver, cache)
    level = dict(ladder.start)

    def job(g: tuple) -> tuple:  # the part and mesh settings of g's current level
        return group_job(geo[g], levels[level[g]][1])

    order = sorted(geo, key=lambda g: getattr(estimate_part(*job(g)), "tets", math.inf))
    prefetch([job(g) for g in order], cache)
    start_compiling(cache)  # a first run after an install: numba compiles while the meshes are made
    queue, sink, done = collections.deque(order), Sink(), 0
    while queue:
        try:
            g = next_ready(queue, lambda g: mesh_state(*job(g), cache))
        except BaseException:  # interrupted while waiting: the mesher processes end too
            pool.cancel()
            raise
        queue.remove(g)
        k = level[g]
        name, s = levels[k]
        t0 = time.perf_counter()
        observer.stage(f"solving part {geo[g][0][1].name}" + (f" ({name})" if name else "")
                       + (f" · {done} of {len(cases)} cases done" if done else ""))
        out = plan.solve(geo[g], s, ctx.solver, cache)
        ladder.tried(g, name, s, out, time.perf_counter() - t0)
        step = next_step(out, k, levels, plan.judge)
        if not step.final:
            ladder.skipped(g, step.skipped)
            level[g] = step.next_level
            # the cap's mesh too, after the next level's: a part that climbs once often climbs on,
            # and then its FE would wait for the mesh (made while the other parts solve)
            cap = [group_job(geo[g], levels[-1][1])] if level[g] < len(levels) - 1 else []
            prefetch([job(g)] + cap, cache, keep=True)
            queue.append(g)
            out = None  # free this level's model, matrix and factor before the next part's
            trim_heap()
            continue
        ladder.stopped(g, k)
        out = [dataclasses.replace(r, level=name, stopped=step.stopped, ladder=tuple(ladder.tried_levels[g]))
               for r in out]
        sink.final(geo[g], out if plan.frames is None else finish(out, plan.frames))
        out = None
        trim_heap()  # what the part's solve and the reduction freed goes back to the system
        done += len(geo[g])
    return [sink.results[id(case)] for _, case in cases]


class _Ladders:
    """Where each part geometry's ladder starts (a warm check starts where the last one stopped:
    the levels it discarded are not loaded again), what it tried, and storing where it stopped."""

    def __init__(self, geo: dict, levels: list, solver: str, cache: Cache) -> None:
        names = [n for n, _ in levels]
        self.cache = cache
        self.keys = {g: ladder_inputs(group, levels, solver) if len(levels) > 1 else None for g, group in geo.items()}
        climbed = {g: read_ladder(k, cache) if k else None for g, k in self.keys.items()}
        self.start = {g: names.index(c[-1]["level"]) if c else 0 for g, c in climbed.items()}
        self.tried_levels = {g: list(c[:-1]) if c else [] for g, c in climbed.items()}

    def tried(self, g: tuple, name: str, s, out: list[CaseResult], seconds: float) -> None:
        self.tried_levels[g].append({"level": name, "size_mm": s.size_mm, "local_size_mm": s.near_mm,
                                     "dofs": int(out[0].solution.model.mesh.ndof), "seconds": round(seconds, 3)})

    def skipped(self, g: tuple, names: tuple[str, ...]) -> None:
        if names:
            self.tried_levels[g][-1]["skipped"] = list(names)

    def stopped(self, g: tuple, k: int) -> None:
        if self.keys[g] and k != self.start[g]:
            save_ladder(self.keys[g], self.tried_levels[g], self.cache)


def next_ready(queue: collections.deque, state: Callable[[tuple], str], poll_s: float = POLL_S) -> tuple:
    """The first part in ``queue`` whose mesh is ready (``state(g)``: 'ready', 'making' or 'none'),
    waiting while meshes are being made (the estimates only guess which comes first); the queue's
    head when none is being made."""
    while True:
        states = {g: state(g) for g in queue}
        ready = [g for g in queue if states[g] == "ready"]
        if ready or "making" not in states.values():
            return (ready or list(queue))[0]
        time.sleep(poll_s)
