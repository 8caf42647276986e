"""Shared test set-up: the programs the README's test command (``bash tests/run.sh``) installs,
and no silent skip in CI.

A test that runs a program marks it ``@pytest.mark.tool("ccx")``: when the program is missing
the test fails, naming the command that installs it, instead of skipping: the cross-check it
makes must not vanish because a machine lacks a package.  Under ``CI`` (any value but empty,
``0`` or ``false``) a skipped test fails too: CI runs every test.
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


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    outcome = yield
    rep = outcome.get_result()
    if rep.skipped and not hasattr(rep, "wasxfail") and os.environ.get("CI", "") not in ("", "0", "false"):
        reason = rep.longrepr[2].removeprefix("Skipped: ") if isinstance(rep.longrepr, tuple) else rep.longrepr
        rep.outcome, rep.longrepr = "failed", f"skipped in CI ({reason}): CI runs every test"
