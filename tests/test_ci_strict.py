"""Under CI nothing vanishes quietly (issue 39): a module skipped at collection time
(``pytest.importorskip`` or ``pytest.skip(allow_module_level=True)`` at module level) and an
``xfail`` (marked or imperative, failing as expected or passing unexpectedly) fail; outside CI they
keep pytest's meaning.  Each case runs the repository's tests/conftest.py in a pytester sandbox."""

from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[1]
MODULES = {
    "test_importorskip": "import pytest\nnp = pytest.importorskip('a_module_no_machine_has')\n\n"
                         "def test_uses_it():\n    pass\n",
    "test_module_skip": "import pytest\npytest.skip('needs a GPU', allow_module_level=True)\n\n"
                        "def test_uses_it():\n    pass\n",
    "test_xfail_marked": "import pytest\n\n@pytest.mark.xfail(reason='known bug 12')\ndef test_bug():\n"
                         "    assert 1 == 2\n",
    "test_xpass": "import pytest\n\n@pytest.mark.xfail(reason='was broken')\ndef test_fixed():\n    assert 1 == 1\n",
    "test_xfail_call": "import pytest\n\ndef test_gives_up():\n    pytest.xfail('not done yet')\n",
}


@pytest.fixture
def sandbox(pytester):
    pytester.makeconftest((ROOT / "tests" / "conftest.py").read_text())
    pytester.makepyfile(**MODULES)
    return pytester


@pytest.mark.parametrize("module, reason", [("test_importorskip", "a_module_no_machine_has"),
                                            ("test_module_skip", "needs a GPU")])
def test_a_collection_time_skip_fails_under_ci(sandbox, monkeypatch, module, reason):
    monkeypatch.setenv("CI", "true")
    res = sandbox.runpytest_inprocess(f"{module}.py", "-rA")
    res.assert_outcomes(errors=1)
    assert res.ret != 0
    res.stdout.fnmatch_lines([f"*skipped at collection in CI*{reason}*CI runs every test*"])


@pytest.mark.parametrize("module, what", [("test_xfail_marked", "failed as expected"),
                                          ("test_xpass", "passed though expected to fail"),
                                          ("test_xfail_call", "failed as expected")])
def test_an_xfail_fails_under_ci(sandbox, monkeypatch, module, what):
    monkeypatch.setenv("CI", "1")
    res = sandbox.runpytest_inprocess(f"{module}.py", "-rA")
    res.assert_outcomes(failed=1)
    assert res.ret != 0
    res.stdout.fnmatch_lines([f"*xfail in CI*{what}*"])


def test_outside_ci_skips_and_xfails_keep_their_meaning(sandbox, monkeypatch):
    monkeypatch.setenv("CI", "false")
    res = sandbox.runpytest_inprocess("-rA")
    res.assert_outcomes(skipped=2, xfailed=2, xpassed=1)
    assert res.ret == 0
