"""Result folders that never lose a result or a user file.

- A check writes everything into a temporary sibling folder and renames it into place at the
  end, so a failed or interrupted run (exception, Ctrl-C, SIGTERM) leaves nothing half-written
  and no temporary folder behind.
- Every result folder carries the marker file :data:`MARKER`; ``--force`` replaces only a
  folder with that marker (a folder rigfem wrote), never a user's own folder.
- A lock file beside the folder (``.<name>.lock``, created with O_EXCL) refuses a second run
  on the same folder while one runs; a lock left by a dead process is taken over.
- Writability is checked before any computation and again at the final rename.
- The folder gets the permissions the umask gives a new folder (``mkdtemp`` makes 0700): others
  on a shared machine read a report as they read the user's other files.
- Names: a name longer than the file system takes is refused naming the option; hidden siblings
  (temporary folder, lock) have short names whatever the folder's.
- A result folder that holds the cache folder (or lies inside it) is refused: replacing the
  folder would delete the cache, the cache's eviction the result.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import hashlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from rigfem.errors import InputError, NoSpaceError, plain
from rigfem.files import NO_SPACE, umask

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


def _limit(base: Path, name: str, default: int) -> int:
    try:
        return os.pathconf(base, name)
    except (OSError, ValueError):
        return default


def check_names(what: str, text: str, path: Path, base: Path) -> None:
    """Refuse a path the file system at ``base`` cannot name: a component longer than its name
    limit (255 bytes on most), or the whole path longer than its path limit (4096 bytes)."""
    longest = max(path.parts, key=lambda part: len(os.fsencode(part)))
    name_max = _limit(base, "PC_NAME_MAX", 255)
    if len(os.fsencode(longest)) > name_max:
        raise InputError(f"{what} = {plain(text, 60)!r}: the name {plain(longest, 40)!r} is "
                         f"{len(os.fsencode(longest))} bytes, more than the {name_max} the file system allows")
    path_max = _limit(base, "PC_PATH_MAX", 4096)
    if len(os.fsencode(str(path))) >= path_max:
        raise InputError(f"{what} = {plain(text, 60)!r}: the path is {len(os.fsencode(str(path)))} bytes, more "
                         f"than the {path_max - 1} the file system allows")


def check_cache_apart(what: str, out: Path) -> None:
    """Refuse a result folder that holds rigfem's cache folder or lies inside it (naming both)."""
    from rigfem.cache import environment_root

    out, cache = Path(os.path.abspath(out)), Path(os.path.abspath(environment_root()))
    if cache == out or cache.is_relative_to(out):
        raise InputError(f"{what} {plain(out, 100)} holds rigfem's cache folder {plain(cache, 100)} "
                         f"(RIGFEM_CACHE); a result folder is replaced whole, which would delete the cache: "
                         f"choose another {what} or move the cache")
    if out.is_relative_to(cache):
        raise InputError(f"{what} {plain(out, 100)} lies inside rigfem's cache folder {plain(cache, 100)} "
                         f"(RIGFEM_CACHE), whose clearing would delete it: choose another {what}")


def check_target(out: Path, what: str = "--out") -> None:
    """Refuse early an output path that cannot be written: its nearest existing ancestor
    must be a writable folder, the names fit the file system, and the cache is not inside it."""
    out = Path(out)
    base = _existing_parent(out.parent)
    check_names(what, str(out), out.absolute(), base)
    check_cache_apart(what, out)
    if not base.is_dir():
        raise InputError(f"{what} {plain(out, 120)}: {plain(base, 120)} is not a folder")
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"{what} {plain(out, 120)}: folder {plain(base, 120)} is not writable")


def check_writable(out: Path, force: bool) -> None:
    """Refuse early (before any computation) a result folder that may not be written: an
    existing folder without ``force``, anything rigfem did not write, an unwritable place."""
    out = Path(out)
    check_names("--out", str(out), out.absolute(), _existing_parent(out.parent))
    check_cache_apart("--out", out)
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


def _short(name: str) -> str:
    """``name`` itself if its hidden siblings' names fit in 255 bytes, else its first 40
    characters and a hash of the whole (still one per folder name)."""
    if len(os.fsencode(name)) <= 200:
        return name
    return f"{name[:40]}-{hashlib.sha256(os.fsencode(name)).hexdigest()[:16]}"


def _lock_path(out: Path) -> Path:
    return out.with_name(f".{_short(out.name)}.lock")


def _made(prefix: str, suffix: str, parent: Path) -> Path:
    """A new hidden folder in ``parent`` with the permissions the umask gives (mkdtemp: 0700)."""
    p = Path(tempfile.mkdtemp(prefix=prefix, suffix=suffix, dir=parent))
    os.chmod(p, 0o777 & ~umask())
    return p


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
                pid = int(lock.read_text(encoding="ascii").strip() or 0)
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
def _no_space_in(tmp: Path, out: Path) -> Iterator[None]:
    """A full disk while writing into ``tmp``: NoSpaceError naming the result folder ``out`` (and
    the file, where the writer said which), not the hidden temporary folder."""
    try:
        yield
    except OSError as exc:
        if not isinstance(exc, NoSpaceError) and exc.errno not in NO_SPACE:
            raise
        text = str(exc) if isinstance(exc, NoSpaceError) else (
            f"could not write the result folder {out}: "
            f"{'the file-size limit (ulimit -f) is reached' if exc.errno == errno.EFBIG else 'no space left'} in {out.parent}")
        raise NoSpaceError(plain(text.replace(str(tmp), str(out)), 400)) from None


@contextlib.contextmanager
def atomic_dir(out: Path, force: bool = False) -> Iterator[Path]:
    """Yield a temporary folder that replaces ``out`` only if the block completes.

    The caller holds :func:`folder_lock`; the target is checked again (marker, writability)
    just before the rename, since the world may have changed during the computation.  A full
    disk (or file-size limit) while the block writes is :class:`NoSpaceError` naming ``out``.
    """
    out = Path(out)
    check_writable(out, force)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = _made(f".{out.name[:40]}.", ".tmp", out.parent)
    old = None
    try:
        with _no_space_in(tmp, out):
            yield tmp
        (tmp / MARKER).write_text("written by rigfem; rigfem --force may replace this folder\n", encoding="utf-8")
        check_writable(out, force)
        if out.exists():
            old = _made(f".{out.name[:40]}.", ".old", out.parent)
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
