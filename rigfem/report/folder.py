"""Atomic result folders: a check writes everything into a temporary sibling folder and
renames it into place at the end, so a failed or interrupted run leaves nothing half-written
and an existing result is never silently overwritten.
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from rigfem.errors import InputError


def check_writable(out: Path, force: bool) -> None:
    """Refuse early (before any computation) to overwrite an existing result folder."""
    if out.exists() and not force:
        raise InputError(f"--out {out} already exists; pass --force to replace it")
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} exists and is not a folder")


@contextlib.contextmanager
def atomic_dir(out: Path, force: bool = False) -> Iterator[Path]:
    """Yield a temporary folder that replaces ``out`` only if the block completes."""
    out = Path(out)
    check_writable(out, force)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
    try:
        yield tmp
        if out.exists():
            old = out.with_name(f".{out.name}.old")
            shutil.rmtree(old, ignore_errors=True)
            out.rename(old)
            tmp.rename(out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            tmp.rename(out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
