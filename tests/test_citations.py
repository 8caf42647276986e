"""Every document the repository cites is in the repository, and every cited § is a heading in it.

A citation is ``NAME.md §N`` (or ``§N-M``), or a Markdown path: ``dir/name.md``, or a bare
``NAME.md`` whose name starts with a capital (a document such as the README; lower-case bare
names are files a command writes, e.g. ``report.md``, and so is a ``results/`` path named in code).  A cited path is resolved from the
repository's top and from the citing file's folder; a link of the docs (and of the two scripts that write
their pages, docs/gen.py and benchmarks/publish.py) may also name a page docs/gen.py generates when the site
is built, resolved from docs/ and its folders (``mkdocs build --strict`` in tests/test_docs.py checks every
such link and anchor on the built site).
"""

import pathlib
import re
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
CITATION = re.compile(r"(?<![\w/.<{*$~-])((?:[\w.-]+/)*([\w-]+)\.md)(?:\s*§\s*(\d+)(?:\s*[-–]\s*(\d+))?)?")


def _files() -> list[pathlib.Path]:
    """The repository's .py, .md and .toml files (tracked or new, not ignored)."""
    out = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout.split()
    return [ROOT / f for f in out if f.endswith((".py", ".md", ".toml")) and (ROOT / f).is_file()]


def _sections(doc: pathlib.Path) -> set[int]:
    """Numbers of the numbered headings of a Markdown file (``## 3. Title``)."""
    return {int(m) for m in re.findall(r"^#+\s*(\d+)[.)\s]", doc.read_text(), re.M)}


DOCS = ROOT / "docs"
_GENERATED: set[pathlib.Path] = set()


def _generated() -> set[pathlib.Path]:
    """The pages docs/gen.py generates at build time, as paths under docs/."""
    if not _GENERATED:
        import importlib.util

        spec = importlib.util.spec_from_file_location("docs_gen", DOCS / "gen.py")
        gen = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(gen)
        _GENERATED.update((DOCS / uri).resolve() for uri in gen.pages())
    return _GENERATED


def _docs_page(path: pathlib.Path, ref: str) -> pathlib.Path | None:
    """A page (on disk or generated) a docs link names (from the page's folder, or for the page-writing scripts from docs/)."""
    if DOCS not in path.parents and path not in (DOCS / "gen.py", ROOT / "benchmarks" / "publish.py"):
        return None
    bases = [path.parent] if DOCS in path.parents and path.suffix == ".md" else [DOCS, *(d for d in DOCS.iterdir()
                                                                                         if d.is_dir())]
    return next((p for b in bases if (p := (b / ref).resolve()).is_file() or p in _generated()), None)


def citations(path: pathlib.Path) -> list[tuple[str, pathlib.Path | None, list[int]]]:
    """(as written, the file it resolves to or None, the § numbers cited) of one file's citations."""
    out = []
    for m in CITATION.finditer(path.read_text(errors="ignore")):
        ref, stem, a, b = m.groups()
        if a is None and "/" not in ref and not stem[0].isupper():
            continue  # a file a command writes (report.md), not a document
        if path.suffix == ".py" and ref.startswith("results/"):
            continue  # code naming the result file it writes, not a document it cites
        doc = next((p for p in (ROOT / ref, path.parent / ref) if p.is_file()), None) or _docs_page(path, ref)
        secs = list(range(int(a), int(b or a) + 1)) if a else []
        out.append((m.group(0), doc, secs))
    return out


def test_every_cited_document_and_section_exists():
    bad = []
    for f in _files():
        if f == pathlib.Path(__file__).resolve():
            continue
        for text, doc, secs in citations(f):
            if doc is None:
                bad.append(f"{f.relative_to(ROOT)}: {text!r} cites a file the repository lacks")
            elif secs and (missing := [s for s in secs if s not in _sections(doc)]):
                bad.append(f"{f.relative_to(ROOT)}: {text!r}: no section {missing} in {doc.relative_to(ROOT)}")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("text, ok", [("see RIG.md §3", False), ("see geometry/RIG.md §3", True),
                                      ("geometry/RIG.md §3-4", True), ("geometry/RIG.md §9", False),
                                      ("geometry/MECHANISMS.md §5", True), ("writes report.md", True),
                                      ("a NOTES.md file", False), ("docs/guide.md", False)])
def test_the_checker_catches_a_bad_citation(tmp_path, text, ok):
    f = tmp_path / "x.py"
    f.write_text(f"# {text}\n")
    found = [(doc is not None and all(s in _sections(doc) for s in secs)) for _, doc, secs in citations(f)]
    assert all(found) == ok
