"""CI runs what README claims: the README's test command is the one .ci/run runs, a missing
program fails the tests that need it, and under CI no test may skip."""

import re
import subprocess
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
    start = readme.index("## Set-up on a fresh machine")
    setup = readme[start:readme.index("\n## ", start)]
    commands = re.findall(r"^    (\S.*)$", setup, re.M)
    assert len(commands) == 2 and "rigfem check" in commands[0]
    test_command = commands[1]
    ci = [line for line in (ROOT / ".ci" / "run").read_text().splitlines() if line and not line.startswith("#")]
    assert ci[-2:] == [test_command, f"{test_command} -m heavy --durations=10"]


@pytest.mark.parametrize("uid, message", [("0", "apt-get could not install calculix-ccx chromium"),
                                          ("1000", "sudo apt-get install -y calculix-ccx chromium")])
def test_run_sh_stops_when_the_debian_packages_cannot_be_installed(tmp_path, uid, message):
    """No package installed (a stand-in dpkg-query), apt-get failing (a stand-in that exits
    100): as root the failed install, as a user the command to run, and nothing built."""
    fake = tmp_path / "bin"
    fake.mkdir()
    for name, body in (("dpkg-query", "exit 1"), ("apt-get", "exit 100"), ("id", f"echo {uid}")):
        (fake / name).write_text(f"#!/bin/sh\n{body}\n")
        (fake / name).chmod(0o755)
    env = {"PATH": f"{fake}:/usr/bin:/bin", "RIGFEM_VENV": str(tmp_path / "venv"), "HOME": str(tmp_path)}
    res = subprocess.run(["bash", str(ROOT / "tests" / "run.sh")], env=env, capture_output=True, text=True,
                         stdin=subprocess.DEVNULL, timeout=60)
    assert res.returncode == 1 and message in res.stderr, res.stderr
    assert not (tmp_path / "venv").exists()
