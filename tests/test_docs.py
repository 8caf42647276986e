"""Docstring examples are documentation that runs: every ``>>>`` in the package is executed."""

import doctest
import importlib
import pathlib

import pytest

import rigfem

PKG = pathlib.Path(rigfem.__file__).parent
WITH_EXAMPLES = sorted(
    ".".join(("rigfem", *f.relative_to(PKG).with_suffix("").parts))
    for f in PKG.rglob("*.py") if ">>>" in f.read_text() and f.name != "__init__.py")


def test_examples_exist():
    assert len(WITH_EXAMPLES) >= 5


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_docstring_examples(name):
    mod = importlib.import_module(name)
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0
