"""The refinement policy: which mesh level a part geometry is solved at next, and when it stops.

A check climbs its levels (``settings.levels()``: the adaptive ladder, coarsest first) part by
part and stops a part at the first level where all its cases are *settled* — a finer mesh cannot
change what the report says of them — or at the last level (the cap).  What settled means is the
verdict layer's (:class:`Judge`, implemented by :class:`rigfem.verdict.part.Target`); this module
only walks the levels.  A level at which a case would stay unsettled even with its band narrowed
at the asymptotic rate (:func:`best_shrink`) is skipped.
"""

from __future__ import annotations

import dataclasses
from typing import Protocol

from rigfem.fe.partcase import CaseResult
from rigfem.verdict.part import Outcome

__all__ = ["Judge", "Step", "best_shrink", "next_step"]


class Judge(Protocol):
    """Whether a finer mesh could change what the report says of a case (the verdict layer's)."""

    def settled(self, outcome: Outcome, shrink: float = 1.0) -> bool:
        """True when ``outcome`` is settled with its error band narrowed by ``shrink``."""


def best_shrink(coarse, fine, order: int) -> float:
    """How much a peak's error band narrows from mesh settings ``coarse`` to ``fine`` at the
    asymptotic rate of order-p elements' stress error, h^p, h the smaller of the global and the
    local size ratios.  A heuristic: a level at which a case would stay unsettled with its band
    narrowed so much, its peak unchanged, is skipped.  A skip costs time (a finer level than
    needed), never the verdict: the part is still judged where it stops."""
    return min(fine.size_mm / coarse.size_mm, fine.near_mm / coarse.near_mm) ** order


@dataclasses.dataclass(frozen=True)
class Step:
    """Where a part goes after a level: ``final`` (and why), or the next level and the ones skipped."""

    final: bool
    stopped: str = ""
    next_level: int = -1
    skipped: tuple[str, ...] = ()


def next_step(results: list[CaseResult], k: int, levels: list[tuple[str, object]], judge: Judge | None) -> Step:
    """The step after solving a part's cases ``results`` at level ``k`` of ``levels``."""
    last = len(levels) - 1
    if judge is None or not last:
        return Step(True, "fixed mesh (no ladder)")
    if all(judge.settled(r.outcome) for r in results):
        return Step(True, "decided within the reporting target")
    if k == last:
        return Step(True, "reached the cap")
    s, skipped = levels[k][1], []
    while k + 1 < last and not all(judge.settled(r.outcome, best_shrink(s, levels[k + 1][1], s.order))
                                   for r in results):
        k += 1  # unsettled there even at the asymptotic rate: skipped
        skipped.append(levels[k][0])
    return Step(False, next_level=k + 1, skipped=tuple(skipped))
