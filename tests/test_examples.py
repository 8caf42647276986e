"""The examples gallery runs: every script in examples/ runs as a user would run it and prints what
its gallery page shows (the ``Prints`` block of its docstring, which docs/gen.py puts on the page;
``...`` stands for what differs from run to run, such as a temporary folder)."""

import doctest
import importlib.util
import pathlib
import runpy

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
_spec = importlib.util.spec_from_file_location("docs_gen", ROOT / "docs" / "gen.py")
gen = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gen)
GALLERY = {e["file"]: e for e in gen.examples()}


def matches(expected: str, got: str) -> bool:
    """doctest's comparison: ``...`` matches anything, runs of whitespace are equal."""
    return doctest.OutputChecker().check_output(expected.strip() + "\n", got.strip() + "\n",
                                                doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)


def test_every_example_is_in_the_gallery_with_its_output():
    assert sorted(GALLERY) == sorted(p.name for p in EXAMPLES.glob("*.py")) and len(GALLERY) >= 5
    for name, e in GALLERY.items():
        assert e["title"] and e["text"], f"{name}: no title or description in its docstring"
        assert e["output"].strip(), f"{name}: its docstring has no 'Prints' block (the gallery shows it)"
    pages = gen.gallery()
    assert all(f"examples/{e['name']}.md" in pages for e in GALLERY.values())


def test_matches_catches_a_changed_figure():
    assert matches("peak 157.3 MPa\nreport in .../my-rig", "peak 157.3 MPa\nreport in /tmp/x/my-rig\n")
    assert not matches("peak 157.3 MPa", "peak 157.4 MPa")


@pytest.mark.parametrize("name", sorted(GALLERY))
def test_example(name, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("sys.argv", [name, str(tmp_path)])
    runpy.run_path(str(EXAMPLES / name), run_name="__main__")
    out = capsys.readouterr().out
    assert matches(GALLERY[name]["output"], out), \
        f"examples/{name} printed\n{out}\nbut its gallery page (docstring 'Prints' block) shows\n{GALLERY[name]['output']}"
