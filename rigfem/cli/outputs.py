"""Output files named on the command line: checked before any computation, never overwritten
unless asked, written whole (a temporary file renamed into place)."""

from __future__ import annotations

import os
from pathlib import Path

from rigfem.errors import InputError


def new_output(flag: str, path: str | None, suffix: str, force: bool | None = None) -> Path | None:
    """``path`` as a Path after checking its suffix, its folder and that it does not exist
    (unless ``force``; None: the command has no --force)."""
    if path is None:
        return None
    if not str(path).lower().endswith(suffix):
        raise InputError(f"{flag} = {path!r} must be a {suffix} path")
    p = Path(path)
    if p.exists() and not force:
        raise InputError(f"{flag}: {path} already exists; " + ("pass --force to overwrite it" if force is not None
                                                                else "refusing to overwrite it"))
    if not p.parent.is_dir():
        raise InputError(f"{flag}: folder {str(p.parent)!r} does not exist")
    return p


def write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` whole: a temporary file beside it, renamed into place."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(text)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
