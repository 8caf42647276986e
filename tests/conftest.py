"""Shared test set-up: the programs the README's test command (``bash tests/run.sh``) installs,
and no silent skip in CI.

A test that runs a program marks it ``@pytest.mark.tool("ccx")``: when the program is missing
the test fails, naming the command that installs it, instead of skipping: the cross-check it
makes must not vanish because a machine lacks a package.  Under ``CI`` (any value but empty,
``0`` or ``false``) a skipped test fails too: CI runs every test.  So does a module skipped while
it is collected (``pytest.importorskip`` or ``pytest.skip(allow_module_level=True)`` at module
level: the collection error names the reason) and a test marked or made ``xfail`` (expected to
fail, or passing unexpectedly): a check CI runs either holds or is fixed, never expected to fail.

The tests are harmless to the machine they run on: for the whole run ``HOME``, the rigfem cache
(``RIGFEM_CACHE``) and the per-user folders programs write (XDG cache, config and data,
matplotlib's) point into one temporary folder, removed at the end; a README command such as
``rigfem cache --clear`` clears that, never the user's cache (tests/test_harmless.py).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest

#: the variables :func:`private_home` points into the run's temporary folder, and where
PRIVATE = {"HOME": "home", "RIGFEM_CACHE": "cache", "XDG_CACHE_HOME": "home/.cache",
           "XDG_CONFIG_HOME": "home/.config", "XDG_DATA_HOME": "home/.local/share",
           "MPLCONFIGDIR": "home/.config/matplotlib"}
#: the run's temporary folder, made once per run: a conftest imported again inside the run (pytester's
#: in-process sandboxes in tests/test_ci*.py) finds it in the environment and keeps it
ROOT_ENV = "RIGFEM_TESTS_ROOT"
_OWN = ROOT_ENV not in os.environ
#: the user's own values, for tests/test_harmless.py to compare with
USER_ENV = {k: os.environ.get(k) for k in PRIVATE}
ROOT = Path(tempfile.mkdtemp(prefix="rigfem-tests-")) if _OWN else Path(os.environ[ROOT_ENV])
os.environ[ROOT_ENV] = str(ROOT)


#: set by tools/mutation_testing.py: keep its RIGFEM_CACHE, a folder rigfem refuses (no cache), since
#: its mutants share one package hash and a cache entry one computed would hide another
KEEP_CACHE_ENV = "RIGFEM_TESTS_KEEP_CACHE"


def private_home(root: Path) -> None:
    """Point HOME, the cache and the per-user folders into ``root``."""
    for var, sub in PRIVATE.items():
        if var == "RIGFEM_CACHE" and os.environ.get(KEEP_CACHE_ENV):
            continue
        (root / sub).mkdir(parents=True, exist_ok=True)
        os.environ[var] = str(root / sub)


private_home(ROOT)  # at import: before pytest imports any test module (and rigfem with it)


def pytest_unconfigure(config: pytest.Config) -> None:
    if _OWN:
        shutil.rmtree(ROOT, ignore_errors=True)

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
