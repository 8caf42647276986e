"""The public API is held against a committed list: a name added to or dropped from an ``__all__``
is a deliberate change, made by editing tests/public_api.txt in the same commit.

The API is every subpackage's ``__all__`` (what README, docs, examples, benchmarks, tests and the
other packages use) and the top-level modules'; ``rigfem.studies``, the deprecated aliases of
rigfem.sweep/verification/design, is held by tests/test_architecture.py.
"""

import importlib
import pathlib

import rigfem

PKG = pathlib.Path(rigfem.__file__).parent
LISTED = pathlib.Path(__file__).with_name("public_api.txt")


def _api_modules() -> list[str]:
    """The subpackages and top-level modules that name an ``__all__`` (rigfem.studies aside)."""
    subs = [f"rigfem.{p.parent.name}" for p in PKG.glob("*/__init__.py") if "__all__" in p.read_text()]
    tops = [f"rigfem.{p.stem}" for p in PKG.glob("*.py") if p.stem != "__init__" and "__all__" in p.read_text()]
    return sorted(m for m in subs + tops if m != "rigfem.studies")


def public_names() -> list[str]:
    """Every ``module.name`` of the public API, sorted."""
    return sorted(f"{m}.{n}" for m in _api_modules() for n in importlib.import_module(m).__all__)


def _difference(now: list[str], listed: list[str]) -> str:
    added, removed = sorted(set(now) - set(listed)), sorted(set(listed) - set(now))
    return "" if not (added or removed) else (
        f"the public API changed: added {added}, removed {removed}; if deliberate, update "
        f"tests/public_api.txt (a renamed public name keeps a deprecated alias for a minor version)")


def test_public_api_matches_the_committed_list():
    """The union of every ``__all__`` is tests/public_api.txt, name for name."""
    assert _difference(public_names(), LISTED.read_text().split()) == ""


def test_a_changed_api_fails_with_its_names():
    """A name dropped from (or added to) an ``__all__`` is reported by name."""
    listed = LISTED.read_text().split()
    msg = _difference(listed[1:], listed)
    assert f"removed [{listed[0]!r}]" in msg and "update tests/public_api.txt" in msg
    assert "added ['rigfem.fe.new_name']" in _difference(listed + ["rigfem.fe.new_name"], listed)
