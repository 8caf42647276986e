"""The check's stages composed for tests that look between them (rigfem.pipeline composes them for users)."""

from rigfem.cache import from_environment
from rigfem.context import Context
from rigfem.fe.executor import Plan, solve_cases
from rigfem.fe.partcase import solve_group
from rigfem.job import Request, read_job
from rigfem.pipeline import load_cases
from rigfem.report.entries import part_entry
from rigfem.verdict.part import Target, judge


def job_of(scene: str = "final-cm", overrides: dict | None = None, allow: bool = False):
    """The read job of a scene (with the environment's cache)."""
    return read_job(Request(scene, overrides or {}, allow), from_environment())


def solved(scene: str = "final-cm", overrides: dict | None = None, whole: bool = False, solve=solve_group):
    """(job, reactions, results) of a check of ``scene``; ``whole``: every result keeps its whole
    solution (any combination can be asked of it), else what a check keeps; ``solve`` the FE stage's
    part solver (a test's recording one)."""
    job = job_of(scene, overrides)
    ctx = Context(from_environment())
    reactions, cases = load_cases(job, ctx)
    plan = Plan(Target(job.settings), None if whole else job.frames, solve)
    return job, reactions, solve_cases(cases, job.settings, plan, ctx)


def recording(levels: list):
    """A part solver that records the mesh level (its global size, mm) of every part it solves."""
    def solve(group, settings, solver, cache):
        levels.append(settings.size_mm)
        return solve_group(group, settings, solver, cache)
    return solve


def entries(job, results) -> list[dict]:
    """The report entries of solved results (the verdict stage, then the report's part entries)."""
    verdicts = judge([r.outcome for r in results], job.settings)
    return [part_entry(r, pv, job.settings) for r, pv in zip(results, verdicts.parts)]
