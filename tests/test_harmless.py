"""The test run is harmless to the machine it runs on (issue 38): HOME, the rigfem cache and the
per-user folders programs write point into the run's own temporary folder for the whole run
(tests/conftest.py), so a README command such as ``rigfem cache --clear``
(tests/test_readme_commands.py) clears that folder, never the user's cache."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import conftest


def test_home_cache_and_user_folders_are_the_runs_own():
    root = conftest.ROOT
    assert root.is_relative_to(tempfile.gettempdir()) and root.name.startswith("rigfem-tests-")
    for var in conftest.PRIVATE:
        assert Path(os.environ[var]).is_relative_to(root), var
        assert os.environ[var] != conftest.USER_ENV[var], var
    assert Path.home().is_relative_to(root) and Path("~").expanduser().is_relative_to(root)


def test_a_rigfem_command_run_by_a_test_sees_the_runs_cache(tmp_path):
    """What README's `rigfem cache --clear` would clear, asked of the command a test runs."""
    r = subprocess.run([sys.executable, "-m", "rigfem", "cache"], capture_output=True, text=True, cwd=tmp_path,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    folder = Path(r.stdout.splitlines()[0].split()[1])
    assert folder.is_relative_to(conftest.ROOT), r.stdout
    user = conftest.USER_ENV["RIGFEM_CACHE"] or str(Path(conftest.USER_ENV["HOME"] or "/nonexistent") / ".cache/rigfem")
    assert not folder.is_relative_to(user) and not Path(user).is_relative_to(folder)
