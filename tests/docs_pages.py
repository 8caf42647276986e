"""The pages whose commands and snippets the tests run: README.md and every Markdown page under docs/,
plus the pages docs/gen.py generates when the site is built.  Shared by tests/test_docs.py and
tests/test_readme_commands.py."""

from __future__ import annotations

import importlib.util
import os
import re
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def gen():
    """docs/gen.py, the generator of the reference pages and the gallery (an MkDocs hook, not a package)."""
    spec = importlib.util.spec_from_file_location("docs_gen", DOCS / "gen.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def pages() -> dict[str, str]:
    """README, the written pages of the docs and the reference pages docs/gen.py generates, by path from
    the repository's root (the gallery's pages are not here: tests/test_examples.py runs their scripts)."""
    found = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
    out = {str(p.relative_to(ROOT)): p.read_text() for p in found}
    out |= {f"docs/{uri} (generated)": text for uri, text in gen().pages(strict=False).items() if not uri.startswith("examples/")}
    return out


@dataclass
class Block:
    page: str
    line: int          #: 1-based line of the opening fence
    lang: str
    title: str | None  #: ``title="NAME"``: the file the page says this is
    text: str
    output: str | None = None  #: the ``text`` block that follows a python block: what it prints

    @property
    def id(self) -> str:
        return f"{self.page}:{self.line}"


_FENCE = re.compile(r'^```(?P<lang>[\w+-]*)(?:\s+title="(?P<title>[^"]+)")?\s*$')


def blocks(page: str, text: str) -> list[Block]:
    """The fenced code blocks of a page, in order; a ``text`` block right after a python block (at most
    one line of prose between them) is that block's expected output."""
    out: list[Block] = []
    lines = text.split("\n")
    i, prose_since = 0, 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            prose_since += bool(lines[i].strip())
            i += 1
            continue
        start, body = i, []
        i += 1
        while i < len(lines) and lines[i].rstrip() != "```":
            body.append(lines[i])
            i += 1
        b = Block(page, start + 1, m["lang"] or "", m["title"], "\n".join(body) + "\n")
        if b.lang == "text" and out and out[-1].lang == "python" and out[-1].output is None and prose_since <= 1:
            out[-1].output = b.text
        out.append(b)
        i += 1
        prose_since = 0
    return out


def all_blocks() -> list[Block]:
    return [b for page, text in pages().items() for b in blocks(page, text)]


def sandbox_env(base: Path) -> dict[str, str]:
    """The environment a page's command or snippet runs in: HOME and RIGFEM_CACHE in temporary folders
    under ``base`` (never the user's cache: ``rigfem cache --clear`` is among the commands), no browser,
    no display; rigfem as installed (regular or editable)."""
    (base / "home").mkdir(parents=True, exist_ok=True)
    (base / "cache").mkdir(parents=True, exist_ok=True)
    return {**os.environ, "HOME": str(base / "home"), "RIGFEM_CACHE": str(base / "cache"), "BROWSER": "/bin/false",
            "DISPLAY": "", "MPLBACKEND": "Agg"}
