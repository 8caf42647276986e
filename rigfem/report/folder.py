"""Result folders that never lose a result or a user file.

- A check writes everything into a temporary sibling folder and renames it into place at the
  end, so a failed or interrupted run (exception, Ctrl-C, SIGTERM) leaves nothing half-written
  and no temporary folder behind.
- Every result folder carries the marker file :data:`MARKER`; ``--force`` replaces only a
  folder with that marker (a folder rigfem wrote), never a user's own folder.
- A lock file beside the folder (``.<name>.lock``, created with O_EXCL) refuses a second run
  on the same folder while one runs; a lock left by a dead process is taken over.
- Writability is checked before any computation and again at the final rename.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from rigfem.errors import InputError, plain

#: the file that marks a folder as written by rigfem (what ``--force`` may replace)
MARKER = ".rigfem-result"


@dataclasses.dataclass(frozen=True)
class Output:
    """Where and what a check writes: its result folder (None: ``results/<scene>``; replaced only
    with ``force``, and only if rigfem wrote it), the PNG pictures, and each part case as a
    CalculiX deck (``export_inp``)."""

    path: Path | None = None
    force: bool = False
    pictures: bool = True
    export_inp: bool = False


def read_report(folder: str | Path) -> dict:
    """The report dict of a result folder (for pytest limits)."""
    import json

    return json.loads((Path(folder) / "report.json").read_text())


def _existing_parent(p: Path) -> Path:
    p = p.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def check_target(out: Path, what: str = "--out") -> None:
    """Refuse early an output path that cannot be written: its nearest existing ancestor
    must be a writable folder."""
    out = Path(out)
    base = _existing_parent(out.parent)
    if not base.is_dir():
        raise InputError(f"{what} {plain(out, 120)}: {plain(base, 120)} is not a folder")
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"{what} {plain(out, 120)}: folder {plain(base, 120)} is not writable")


def check_writable(out: Path, force: bool) -> None:
    """Refuse early (before any computation) a result folder that may not be written: an
    existing folder without ``force``, anything rigfem did not write, an unwritable place."""
    out = Path(out)
    if out.exists() or out.is_symlink():
        if not force:
            raise InputError(f"--out {plain(out, 120)} already exists; pass --force to replace it")
        if out.is_symlink() or not out.is_dir():
            raise InputError(f"--out {plain(out, 120)} exists and is not a folder; --force replaces only a "
                             f"result folder rigfem wrote")
        if not (out / MARKER).is_file():
            raise InputError(f"--out {plain(out, 120)} is not a rigfem result folder (no {MARKER} file); "
                             f"--force replaces only folders rigfem wrote: choose another --out")
    check_target(out)


def _lock_path(out: Path) -> Path:
    return out.with_name(f".{out.name}.lock")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


@contextlib.contextmanager
def folder_lock(out: Path) -> Iterator[None]:
    """Hold ``.<name>.lock`` beside ``out``; InputError if another live run holds it."""
    lock = _lock_path(Path(out))
    lock.parent.mkdir(parents=True, exist_ok=True)
    for _ in range(2):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            break
        except FileExistsError:
            try:
                pid = int(lock.read_text().strip() or 0)
            except (OSError, ValueError):
                pid = 0
            if pid and _alive(pid):
                raise InputError(f"--out {plain(out, 120)} is being written by another rigfem run (pid {pid}, "
                                 f"lock {plain(lock.name, 60)}); wait for it or choose another --out") from None
            lock.unlink(missing_ok=True)  # left by a run that died without cleaning up
    else:
        raise InputError(f"--out {plain(out, 120)}: cannot take the lock {plain(lock, 120)}")
    try:
        os.write(fd, f"{os.getpid()}\n".encode())
        os.close(fd)
        yield
    finally:
        lock.unlink(missing_ok=True)


@contextlib.contextmanager
def atomic_dir(out: Path, force: bool = False) -> Iterator[Path]:
    """Yield a temporary folder that replaces ``out`` only if the block completes.

    The caller holds :func:`folder_lock`; the target is checked again (marker, writability)
    just before the rename, since the world may have changed during the computation.
    """
    out = Path(out)
    check_writable(out, force)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
    old = None
    try:
        yield tmp
        (tmp / MARKER).write_text("written by rigfem; rigfem --force may replace this folder\n")
        check_writable(out, force)
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".old", dir=out.parent))
            out.rename(old / "result")
        try:
            tmp.rename(out)
        except OSError:
            if old is not None:  # put the previous result back
                (old / "result").rename(out)
                old = None
            raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
