"""Deprecated: ``rigfem check`` is composed in :mod:`rigfem.pipeline` (0.2).

``rigfem.check.run_check(name, out=..., overrides=..., ...)`` and ``read_report`` still work, with a
DeprecationWarning; write ``rigfem.pipeline.run_check(Request(name, overrides), Output(out), ctx)``.
This alias goes in rigfem 0.3.
"""

from __future__ import annotations

import warnings
from pathlib import Path

from rigfem.cache import from_environment
from rigfem.context import Context
from rigfem.observer import Observer
from rigfem.pipeline import Output, Request
from rigfem.pipeline import read_report as _read_report
from rigfem.pipeline import run_check as _run_check
from rigfem.settings import REFERENCE_SCENE

__all__ = ["run_check", "read_report"]


def _warn(old: str, new: str) -> None:
    warnings.warn(f"rigfem.check.{old} is deprecated: use {new}; the alias goes in rigfem 0.3",
                  DeprecationWarning, stacklevel=3)


class _Callbacks(Observer):
    def __init__(self, on_stage, on_verdict) -> None:
        self.on_stage, self.on_verdict = on_stage, on_verdict

    def stage(self, text: str) -> None:
        if self.on_stage:
            self.on_stage(text)

    def decided(self, report: dict) -> None:
        if self.on_verdict:
            self.on_verdict(report)


def run_check(name: str | Path = REFERENCE_SCENE, out: str | Path | None = None, force: bool = False,
              overrides: dict | None = None, quiet: bool = False, solver: str = "auto",
              export_inp: bool = False, allow_rule_violations: bool = False, pictures: bool = True,
              on_verdict=None, on_stage=None) -> dict:
    """Deprecated form of :func:`rigfem.pipeline.run_check` (``quiet`` no longer matters: library
    code prints nothing)."""
    _warn("run_check", "rigfem.pipeline.run_check(Request(scene, overrides), Output(out, force), ctx)")
    ctx = Context(from_environment(), _Callbacks(on_stage, on_verdict), solver)
    output = Output(None if out is None else Path(out), force, pictures, export_inp)
    return _run_check(Request(name, dict(overrides or {}), allow_rule_violations), output, ctx)


def read_report(folder: str | Path) -> dict:
    """Deprecated: :func:`rigfem.pipeline.read_report`."""
    _warn("read_report", "rigfem.pipeline.read_report")
    return _read_report(folder)
