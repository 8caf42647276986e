"""The check's data path, composed in one place.

Each stage is a plain function of the previous stage's product, in the package that holds its
data; this module only composes them::

    Request ─read_job─▶ Job ─linkage_state─▶ LinkageState ─react─▶ Reactions ─part_cases─▶ PartCases
            ─solve_cases─▶ CaseResults ─judge─▶ Verdicts ─document/write_check─▶ report folder

:func:`run_check` is ``rigfem check``; :func:`check` stops before the report (the CalculiX
cross-check and the tests use it).  The sweep and the rig design compose the same stages but
their FE stage, which superposes cached unit bases (:mod:`rigfem.sweep.bases`), and judge with
the same :func:`rigfem.verdict.part.judge`.

>>> import pathlib, tempfile
>>> out = pathlib.Path(tempfile.mkdtemp()) / "final-cm"
>>> report = run_check(Request("final-cm", {"parts": ["plate_A"], "modes": ["original"],
...                                         "fidelity": "draft", "frames": 0}), Output(out))
>>> report["verdict"], report["left_out"], [(p["name"], p["mode"]) for p in report["parts"]]
('pass', '1 of 6 parts (not crank_rail, coupler_rail, rocker_rail, plate_B, post_B), original mode only', [('plate_A', 'original')])
>>> (out / "report.json").is_file()
True
>>> import shutil; shutil.rmtree(out.parent)  # the example's folder, not left behind
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from rigfem.context import Context, default_context
from rigfem.dynamics import cycle, imported
from rigfem.dynamics.history import Reactions
from rigfem.fe.executor import Plan, solve_cases
from rigfem.job import Checked, Job, Request, read_job
from rigfem.linkage.state import linkage_state
from rigfem.loads.cases import part_cases
from rigfem.report.check import document, write_check
from rigfem.report.folder import Output, check_writable, folder_lock, read_report
from rigfem.settings import REFERENCE_SCENE
from rigfem.verdict.part import Target, judge

__all__ = ["Request", "Output", "Context", "check", "load_cases", "solve_job", "run_check", "read_report"]


def load_cases(job: Job, ctx: Context) -> tuple[Reactions, list]:
    """The stages from a read job to its part cases: motion, reactions (the dynamics, or those of the
    job's reactions CSV, read with the job) and part cases (none at a toggle, where the reactions are unbounded)."""
    motion, options = linkage_state(job.linkage, job.crank_deg, job.scene.speed_hz), job.dynamics
    if job.external is not None:
        ctx.observer.stage("reactions from the CSV")
        reactions = imported.react(job.linkage, motion, job.external, options)
    else:
        ctx.observer.stage("dynamics")
        reactions = cycle.react(job.linkage, motion, options)
    return reactions, [] if reactions.singular else part_cases(reactions.history, reactions.peaks, job.settings)


def solve_job(job: Job, ctx: Context) -> Checked:
    """Every stage from a read job to its verdicts: :func:`load_cases`, FE (each part refined until
    its verdict is decided), verdicts."""
    reactions, cases = load_cases(job, ctx)
    results = solve_cases(cases, job.settings, Plan(Target(job.settings), job.frames), ctx) if cases else []
    verdicts = judge([r.outcome for r in results], job.settings, job.rule_violations if job.rig_rules else None,
                     reactions.singular)
    return Checked(job, reactions, tuple(results), verdicts)


def check(request: Request | str | Path = REFERENCE_SCENE, ctx: Context | None = None) -> Checked:
    """A check without its report: the job read from ``request`` and solved."""
    ctx = default_context(ctx)
    return solve_job(read_job(request if isinstance(request, Request) else Request(request), ctx.cache), ctx)


def run_check(request: Request | str | Path = REFERENCE_SCENE, out: Output | str | Path | None = None,
              ctx: Context | None = None) -> dict:
    """``rigfem check``: check a scene, write its result folder (default ``results/<scene>``) and
    return the report dict.  Everything checkable is checked before the computation (the scene,
    its options, the rig rules, the reactions CSV, the result folder); the folder is locked while
    the check runs (a second run on it is refused) and appears only when complete."""
    ctx = default_context(ctx)
    request = request if isinstance(request, Request) else Request(request)
    job = read_job(request, ctx.cache)
    output = out if isinstance(out, Output) else Output(None if out is None else Path(out))
    if output.path is None:
        output = dataclasses.replace(output, path=Path("results") / job.scene.name)
    check_writable(output.path, output.force)
    with folder_lock(output.path):
        checked = solve_job(job, ctx)
        report = document(checked)
        ctx.observer.decided(report)
        return write_check(checked, report, output, ctx)
