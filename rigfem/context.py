"""What every stage of a job shares: where the cache is, who hears progress, the solver, the workers.

Made once at the edge (the command line, or a library call given none) and handed down; no stage
reads the environment.
"""

from __future__ import annotations

import dataclasses

from rigfem.cache import NO_CACHE, Cache, from_environment
from rigfem.errors import check_range
from rigfem.observer import SILENT, Observer

__all__ = ["Context", "default_context"]


@dataclasses.dataclass(frozen=True)
class Context:
    """The cache, the observer, the linear solver (auto | pardiso | superlu | amg) and the worker
    processes a job may use."""

    cache: Cache = NO_CACHE
    observer: Observer = SILENT
    solver: str = "auto"
    workers: int = 1  #: 1-256 (checked as the context is made)

    def __post_init__(self) -> None:
        check_range("workers", self.workers, 1, 256)


def default_context(ctx: Context | None = None) -> Context:
    """``ctx``, or the environment's cache with nobody listening (a library call given none)."""
    return Context(cache=from_environment()) if ctx is None else ctx
