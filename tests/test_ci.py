"""CI runs what README claims: the README's test command is the one .ci/run runs, a missing
program fails the tests that need it, and under CI no test may skip."""

import re
from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[1]
INNER = '''
import pytest

@pytest.mark.tool("ccx")
def test_needs_ccx():
    pass

@pytest.mark.skipif(True, reason="some machine lacks something")
def test_skips():
    pass
'''


@pytest.fixture
def inner(pytester):
    pytester.makeconftest((ROOT / "tests" / "conftest.py").read_text())
    pytester.makepyfile(INNER)
    return pytester


def test_a_missing_program_fails_naming_its_package(inner, monkeypatch, tmp_path):
    monkeypatch.delenv("CI", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))  # an empty folder: no ccx
    res = inner.runpytest_inprocess("-rA")
    res.assert_outcomes(errors=1, skipped=1)
    res.stdout.fnmatch_lines(["*ccx is not on PATH*bash tests/run.sh*apt-get install calculix-ccx*"])


def test_a_skip_fails_under_ci(inner, monkeypatch):
    monkeypatch.setenv("CI", "true")
    res = inner.runpytest_inprocess("-k", "skips", "-rA")
    res.assert_outcomes(errors=1)  # a skip happens while the test is set up
    res.stdout.fnmatch_lines(["*skipped in CI (some machine lacks something): CI runs every test*"])


def test_ci_runs_the_readme_test_command_then_the_heavy_tests():
    readme = (ROOT / "README.md").read_text()
    setup = readme[readme.index("## Set-up on a fresh machine"):readme.index("## The data path")]
    commands = re.findall(r"^    (\S.*)$", setup, re.M)
    assert len(commands) == 2 and "rigfem check" in commands[0]
    test_command = commands[1]
    ci = [line for line in (ROOT / ".ci" / "run").read_text().splitlines() if line and not line.startswith("#")]
    assert ci[-2:] == [test_command, f"{test_command} -m heavy --durations=10"]
