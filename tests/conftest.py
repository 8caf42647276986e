"""Shared test set-up: the programs the README's test command (``bash tests/run.sh``) installs,
and no silent skip in CI.

A test that runs a program marks it ``@pytest.mark.tool("ccx")``: when the program is missing
the test fails, naming the command that installs it, instead of skipping: the cross-check it
makes must not vanish because a machine lacks a package.  Under ``CI`` (any value but empty,
``0`` or ``false``) a skipped test fails too: CI runs every test.  So does a module skipped while
it is collected (``pytest.importorskip`` or ``pytest.skip(allow_module_level=True)`` at module
level: the collection error names the reason) and a test marked or made ``xfail`` (expected to
fail, or passing unexpectedly): a check CI runs either holds or is fixed, never expected to fail.
"""

from __future__ import annotations

import os
import shutil

import pytest

#: the Debian package that provides each program the tests run (tests/run.sh installs them)
TOOLS = {"ccx": "calculix-ccx", "chromium": "chromium"}


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "tool(name): runs a program tests/run.sh installs (ccx, chromium); "
                                       "fails, never skips, when it is missing")


def pytest_runtest_setup(item: pytest.Item) -> None:
    for mark in item.iter_markers("tool"):
        name = mark.args[0]
        if shutil.which(name) is None:
            pytest.fail(f"{name} is not on PATH: run the README's test command `bash tests/run.sh`, "
                        f"or apt-get install {TOOLS[name]}", pytrace=False)


def in_ci() -> bool:
    return os.environ.get("CI", "") not in ("", "0", "false")


def _reason(longrepr) -> str:
    return longrepr[2].removeprefix("Skipped: ") if isinstance(longrepr, tuple) else str(longrepr)


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector: pytest.Collector):
    """Under CI a module (or class) skipped while collected is a collection error, not a skip."""
    outcome = yield
    rep = outcome.get_result()
    if rep.skipped and in_ci():
        rep.outcome, rep.longrepr = "failed", f"skipped at collection in CI ({_reason(rep.longrepr)}): CI runs every test"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    outcome = yield
    rep = outcome.get_result()
    if not in_ci():
        return
    if hasattr(rep, "wasxfail"):  # xfailed (rep.skipped) or xpassed (rep.passed): a failure either way
        what = "failed as expected" if rep.skipped else "passed though expected to fail"
        reason = rep.wasxfail.removeprefix("reason: ") or "no reason given"
        del rep.wasxfail  # else pytest counts the failure as an expected one
        rep.outcome, rep.longrepr = "failed", f"xfail in CI ({reason}): {what}; CI runs every test and wants it to pass"
    elif rep.skipped:
        rep.outcome, rep.longrepr = "failed", f"skipped in CI ({_reason(rep.longrepr)}): CI runs every test"
