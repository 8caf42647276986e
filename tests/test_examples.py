"""The examples in examples/ run as a user would run them, and print what they promise."""

import pathlib
import runpy

import pytest

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"
#: example -> text its output must contain
EXPECT = {
    "check_custom_scene.py": "overall: pass",
    "custom_part.py": "within the error estimate",
    "solve_part.py": "of σu/2 = 375 MPa: pass",
    "textbook_kinematics.py": "transmission angle",
    "small_sweep.py": "comply with every rig rule",
}


def test_every_example_is_run():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(EXPECT)


@pytest.mark.parametrize("name", sorted(EXPECT))
def test_example(name, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("sys.argv", [name, str(tmp_path)])
    runpy.run_path(str(EXAMPLES / name), run_name="__main__")
    assert EXPECT[name] in capsys.readouterr().out
