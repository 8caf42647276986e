"""File helpers every layer uses: the content hash that cache entries and output ledgers keep,
and the one way any file is written whole (a temporary name beside it, renamed when complete).

- Temporary names are short whatever the target's name (a 250-byte name's sibling would pass the
  file system's 255-byte limit): at most 40 characters of the target's stem, the pid and a token.
- ``whole_file(path, replace=False)`` never replaces a file that appeared at ``path`` meanwhile
  (the final step is a hard link, which fails on an existing name, or ``renameat2`` with
  ``RENAME_NOREPLACE`` where links are not supported); ``replace=<SHA-256>`` replaces only the
  file of that content (``--force`` on a file rigfem wrote, unchanged since the check).
- A full disk, a full quota or the file-size limit while writing is :class:`NoSpaceError`
  (could not compute, naming the file and its folder), not an internal error.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import errno
import functools
import hashlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path

from rigfem.errors import NoSpaceError, plain

__all__ = ["file_sha256", "whole_file", "temp_name", "rename_new", "replace_unchanged", "umask", "NO_SPACE"]

#: errno values that mean "the disk (quota, file-size limit) is full"
NO_SPACE = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)
#: characters of a target's stem kept in its temporary sibling's name
_STEM = 40


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's content, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def temp_name(name: str, kind: str = "tmp") -> str:
    """A hidden sibling name for ``name`` well under 255 bytes: ``.<stem[:40]>.<pid>-<token>.<kind><suffix>``
    (the suffix kept, up to 16 characters, so writers pick the format from it).

    >>> len(temp_name("x" * 250 + ".csv").encode()) < 100
    True
    """
    p = Path(name)
    suffix = p.suffix if len(p.suffix) <= 16 else ""
    return f".{p.stem[:_STEM]}.{os.getpid()}-{secrets.token_hex(3)}.{kind}{suffix}"


@functools.lru_cache(maxsize=1)
def _renameat2():
    """glibc's ``renameat2`` (Linux), or None."""
    try:
        fn = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True).renameat2
    except (OSError, AttributeError):
        return None
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    return fn


def rename_new(src: Path, dst: Path) -> None:
    """Move ``src`` to ``dst`` only if no file is at ``dst`` (FileExistsError otherwise), atomically:
    a hard link then an unlink, or ``renameat2(RENAME_NOREPLACE)`` on a file system without links."""
    try:
        os.link(src, dst, follow_symlinks=False)
    except FileExistsError:
        raise
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EMLINK, errno.ENOSYS):
            raise
        fn = _renameat2()
        at_cwd, noreplace = -100, 1  # AT_FDCWD, RENAME_NOREPLACE
        if fn is None or fn(at_cwd, os.fsencode(src), at_cwd, os.fsencode(dst), noreplace) != 0:
            code = ctypes.get_errno() if fn is not None else errno.ENOSYS
            if code not in (errno.ENOSYS, errno.EINVAL):
                raise OSError(code, os.strerror(code), str(dst)) from None
            if os.path.lexists(dst):  # no atomic way here: the narrowest check
                raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(dst)) from None
            os.rename(src, dst)
        return
    os.unlink(src)


def replace_unchanged(src: Path, dst: Path, sha256: str) -> None:
    """Move ``src`` to ``dst`` replacing only the file of content ``sha256`` there (what a check
    found at ``dst``): the old file is first renamed aside, so nothing written to ``dst`` after
    its content is confirmed can be lost; FileExistsError (``dst`` kept as found then) if it
    changed or was replaced meanwhile."""
    aside = dst.with_name(temp_name(dst.name, "old"))
    os.rename(dst, aside)
    if file_sha256(aside) != sha256:
        rename_new(aside, dst)  # put the changed file back (FileExistsError if yet another appeared)
        raise FileExistsError(errno.EEXIST, "changed since it was checked", str(dst))
    try:
        rename_new(src, dst)
    except FileExistsError:  # a file appeared at dst after ours was set aside: keep it
        aside.unlink()
        raise
    aside.unlink()


def umask() -> int:
    """The process's file-mode creation mask (read without changing it where /proc tells it)."""
    with contextlib.suppress(OSError, ValueError, StopIteration):
        with open("/proc/self/status", encoding="ascii") as fh:
            return int(next(line for line in fh if line.startswith("Umask:")).split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def whole_file(path: str | Path, replace: bool | str = True) -> Iterator[Path]:
    """A temporary name beside ``path`` (same suffix, so writers pick the format from it) that is
    renamed to ``path`` when the block completes and removed if it fails or is interrupted:
    every file rigfem writes is whole or absent, never half-written.  ``replace=False``: a file
    found at ``path`` then (one that appeared while the block ran) is kept and FileExistsError
    raised; ``replace`` a SHA-256: only the file of that content is replaced
    (:func:`replace_unchanged`).  A full disk is :class:`NoSpaceError` naming ``path``."""
    path = Path(path)
    tmp = path.with_name(temp_name(path.name))
    try:
        yield tmp
        if replace is True:
            os.replace(tmp, path)
        elif replace is False:
            rename_new(tmp, path)
        else:
            replace_unchanged(tmp, path, replace)
    except OSError as exc:  # a nested whole_file's NoSpaceError names its temporary file: name ours
        if not isinstance(exc, NoSpaceError) and exc.errno not in NO_SPACE:
            raise
        why = {errno.EDQUOT: "the disk quota is exceeded", errno.EFBIG: "the file-size limit (ulimit -f) is reached"}
        raise NoSpaceError(f"could not write {plain(path, 200)}: "
                           f"{why.get(getattr(exc, 'errno', None), 'no space left')} in {plain(path.parent, 200)}"
                           ) from None
    finally:
        tmp.unlink(missing_ok=True)
