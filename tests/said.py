"""What a command said on stderr, its progress lines aside.

A command running longer than 2 s reports its stage on stderr (``rigfem check: meshing part x … 3 s``,
rigfem/cli/progress.py); on a loaded machine even a quick refusal can take that long.  Tests judge
the lines a command means to say (its error, its ``wrote``), never the absence of progress.
"""

from __future__ import annotations

import re

#: a progress line as rigfem/cli/progress.py writes it in a log (a terminal's redraws start with \r)
PROGRESS = re.compile(r"(\r\x1b\[K)*rigfem [^:\n]+: .+ … \d+ s( [|/\\-])?")


def said(err: str | bytes) -> list[str]:
    """The non-empty lines of ``err`` that are not progress lines."""
    text = err.decode(errors="replace") if isinstance(err, bytes) else err
    return [ln for ln in text.splitlines() if ln.strip() and not PROGRESS.fullmatch(ln.strip("\r"))]


def one_line(err: str | bytes) -> str:
    """The one line ``err`` says besides progress (AssertionError showing it all otherwise)."""
    lines = said(err)
    assert len(lines) == 1, err
    return lines[0]
