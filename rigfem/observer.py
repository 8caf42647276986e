"""Who hears a long job's progress: the one object library code reports to.

Library code never prints; a stage function is handed an :class:`Observer` (in its context) and
tells it which stage begins and how far a counted step got.  The default, :data:`SILENT`, hears
nothing; the command line's observer (:mod:`rigfem.cli.progress`) prints.
"""

from __future__ import annotations

__all__ = ["Observer", "SILENT"]


class Observer:
    """Hears progress; every method does nothing here (subclass what you need)."""

    def stage(self, text: str) -> None:
        """A stage begins: 'dynamics', 'meshing part plate_A (coarse)', 'report', ..."""

    def step(self, done: int, total: int, what: str) -> None:
        """``done`` of ``total`` counted steps are finished, the last one ``what`` (a part case, a chunk)."""

    def partial(self, result: dict) -> None:
        """A long study's result so far (kept where the job may stop before the end)."""

    def decided(self, report: dict) -> None:
        """The verdicts are known (``report``: the report dict), before pictures and files are written."""


#: hears nothing
SILENT = Observer()
