"""The physics-mutation safety net (issue 39 §2): tools/physics_mutations.py plants each of its
bugs (load factor ×1.25, a part's loads ×2, stress ×0.8, ZZ estimate ×0.25, E ×2, a bearing
direction dropped, a support released, gravity's sign, the crank speed doubled, and more) in a
scratch copy and runs the tests named for it; every one must make a test fail.  The whole run is
``heavy`` (about 10 min on two cores: CI's ``pytest -m heavy``); the default run checks that every
mutation still applies to the code (a refactor that moves a snippet must move the mutation)."""

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
physics_mutations = importlib.import_module("physics_mutations")  # tools/physics_mutations.py, a script

REQUIRED = {"load_factor_x1.25", "plate_loads_x2", "stress_x0.8", "zz_x0.25", "e_x2", "bearing_direction_dropped",
            "support_released", "gravity_sign_dynamics", "gravity_sign_fe", "crank_speed_x2"}


def test_every_mutation_applies_exactly_once_and_names_existing_tests():
    names = [m.name for m in physics_mutations.MUTATIONS]
    assert len(set(names)) == len(names) and REQUIRED <= set(names)
    assert physics_mutations.check_snippets() == []
    for m in physics_mutations.MUTATIONS:
        assert m.tests and m.snippet != m.replacement, m.name
        for t in m.tests:
            assert (ROOT / t.split("::")[0]).is_file(), (m.name, t)


def test_a_snippet_found_twice_or_not_at_all_is_refused(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\nx = 1\n")
    twice = physics_mutations.Mutation("m", "a.py", "x = 1", "x = 2", ("t",), "")
    gone = physics_mutations.Mutation("n", "a.py", "y = 1", "y = 2", ("t",), "")
    got = physics_mutations.check_snippets([twice, gone], tmp_path)
    assert len(got) == 2 and "2 times" in got[0] and "0 times" in got[1]


@pytest.mark.heavy
def test_every_physics_mutation_fails_a_test():
    res = subprocess.run([sys.executable, str(ROOT / "tools" / "physics_mutations.py")], cwd=ROOT,
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stdout[-4000:] + res.stderr[-4000:]
