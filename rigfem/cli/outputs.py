"""Every file or folder rigfem writes, under one policy: checked before any computation, never
overwritten without ``--force``, ``--force`` replacing only what rigfem wrote, written whole.

- A place that cannot hold the output is refused with one line before anything is computed:
  the current folder or one above it, a path under /proc, /sys or /dev, a file where a folder
  is expected, an unwritable or full destination.
- rigfem records each file it writes in the ledger :data:`LEDGER` of that file's folder (name
  and SHA-256); ``--force`` replaces a file only while its content is still what the ledger says
  (a file the user made or edited since is never replaced).  Result folders carry
  :data:`rigfem.report.folder.MARKER`.
- Every file is written to a temporary name beside it and renamed into place when complete; the
  rename never replaces a file that appeared since the check (another program's, or another rigfem
  run's on the same path): that is refused, the result not written.
- A name longer than the file system takes is bad input naming the option, before any work.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path

from rigfem.errors import InputError, NoSpaceError, plain
from rigfem.files import file_sha256, whole_file
from rigfem.report.folder import MARKER, check_cache_apart, check_names

__all__ = ["LEDGER", "MIN_FREE_BYTES", "check_place", "new_output", "new_folder", "written", "write_text",
           "write_file", "wrote", "mark_folder", "rigfem_wrote"]

#: the file, in each folder rigfem writes into, naming the files rigfem wrote there and their SHA-256
LEDGER = ".rigfem-outputs.json"
#: a destination with less free space than this is refused as full
MIN_FREE_BYTES = 4 * 2**20
_SYSTEM = ("/proc", "/sys", "/dev")
#: output file -> what :func:`new_output` found there: None (nothing) or the SHA-256 of the rigfem
#: file ``--force`` may replace; :func:`written` replaces nothing else
_FOUND: dict[Path, str | None] = {}


def _nearest_existing(p: Path) -> Path:
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def check_place(flag: str, path: str | Path, folder: bool = False) -> Path:
    """``path`` (absolute) if an output may be written there; else InputError naming ``flag``."""
    text = str(path)
    if not text.strip():
        raise InputError(f"{flag} is empty; give a file or folder name")
    p = Path(os.path.abspath(text))
    if p == Path(os.getcwd()) or Path(os.getcwd()).is_relative_to(p):
        raise InputError(f"{flag} = {plain(text, 80)!r} is the current folder or one above it; give a new "
                         f"{'folder' if folder else 'file'} name")
    if any(p == Path(s) or p.is_relative_to(s) for s in _SYSTEM):
        raise InputError(f"{flag} = {plain(text, 80)!r} is under {p.parts[0]}{p.parts[1]}, a system folder; "
                         f"give a path in a folder of yours")
    base = _nearest_existing(p.parent)
    check_names(flag, text, p, base)
    if not base.is_dir():
        raise InputError(f"{flag} = {plain(text, 80)!r}: {plain(base, 80)} is not a folder (it is a file)")
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"{flag} = {plain(text, 80)!r}: folder {plain(base, 80)} is not writable")
    free = shutil.disk_usage(base).free
    if free < MIN_FREE_BYTES:
        raise InputError(f"{flag} = {plain(text, 80)!r}: the disk of {plain(base, 80)} is full "
                         f"({free // 1024} KiB free, need at least {MIN_FREE_BYTES // 2**20} MiB)")
    return p


def _ledger(folder: Path) -> dict[str, str]:
    try:
        data = json.loads((folder / LEDGER).read_text(encoding="utf-8"))
        return data if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


def rigfem_wrote(path: Path) -> bool:
    """True if ``path`` is a file rigfem wrote and nobody changed since (ledger), or lies in a
    result folder rigfem wrote (marker)."""
    path = Path(path)
    if not path.is_file() or path.is_symlink():
        return False
    if (path.parent / MARKER).is_file():
        return True
    return _ledger(path.parent).get(path.name) == file_sha256(path)


def new_output(flag: str, path: str | None, suffix: str | tuple[str, ...], force: bool = False) -> Path | None:
    """The output file ``path`` checked before any computation: its suffix, its place, and that it
    does not exist (or, with ``force``, that rigfem wrote it).  None if not given."""
    if path is None:
        return None
    suffixes = (suffix,) if isinstance(suffix, str) else suffix
    if not str(path).lower().endswith(suffixes):
        raise InputError(f"{flag} = {plain(path, 80)!r} must be a {' or '.join(suffixes)} path")
    p = check_place(flag, path)
    if p.is_dir():
        raise InputError(f"{flag} = {plain(path, 80)!r} is a folder; give a file name")
    if p.exists() or p.is_symlink():
        if not force:
            raise InputError(f"{flag} = {plain(path, 80)!r} already exists; pass --force to replace it "
                             f"(only a file rigfem wrote)")
        if not rigfem_wrote(p):
            raise InputError(f"{flag} = {plain(path, 80)!r} exists and was not written by rigfem (or was changed "
                             f"since); --force replaces only files rigfem wrote: choose another name")
        _FOUND[p] = file_sha256(p)
    else:
        _FOUND[p] = None
    return p


def new_folder(flag: str, path: str | Path, force: bool = False) -> Path:
    """The output folder ``path`` checked before any computation: it does not exist, or (with
    ``force``) it is a result folder rigfem wrote (it holds the marker)."""
    p = check_place(flag, path, folder=True)
    check_cache_apart(flag, p)
    if p.exists() or p.is_symlink():
        if p.is_symlink() or not p.is_dir():
            raise InputError(f"{flag} = {plain(path, 80)!r} exists and is not a folder")
        if not force:
            raise InputError(f"{flag} = {plain(path, 80)!r} already exists; pass --force to write into it "
                             f"(only a folder rigfem wrote)")
        if not (p / MARKER).is_file():
            raise InputError(f"{flag} = {plain(path, 80)!r} is not a rigfem result folder (no {MARKER} file); "
                             f"--force writes only into folders rigfem wrote: choose another folder")
    return p


def mark_folder(path: Path) -> None:
    """Create the output folder ``path`` (and parents) with the result-folder marker."""
    path.mkdir(parents=True, exist_ok=True)
    if not (path / MARKER).exists():
        write_text(path / MARKER, "written by rigfem; rigfem --force may replace the files in this folder\n",
                   record=False)


def _record(path: Path) -> None:
    folder = path.parent
    if (folder / MARKER).is_file():
        return
    ledger = _ledger(folder)
    ledger[path.name] = file_sha256(path)
    with whole_file(folder / LEDGER) as tmp:
        tmp.write_text(json.dumps(ledger, indent=1, sort_keys=True) + "\n", encoding="utf-8")


def _still(path: Path, found: str | None) -> bool:
    """Whether ``path`` is as :func:`new_output` found it: absent, or the rigfem file of that SHA-256."""
    if found is None:
        return not (path.exists() or path.is_symlink())
    return path.is_file() and not path.is_symlink() and file_sha256(path) == found


@contextlib.contextmanager
def written(path: str | Path, record: bool = True) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same suffix, so writers pick the format); rename it
    into place when the block completes, remove it if not.  An output :func:`new_output` checked
    replaces only what it found there: a file that appeared (or changed) since is kept and the
    write refused.  An OSError becomes one line; a full disk stays :class:`NoSpaceError`."""
    path = Path(path)
    checked = Path(os.path.abspath(path))
    found = _FOUND.pop(checked, False)
    appeared = InputError(f"{plain(path, 120)} appeared (or changed) while rigfem ran: it was not replaced "
                          f"and this result was not written; run again with another name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if found is not False and not _still(path, found):
            raise appeared
        with whole_file(path, replace=True if found is False else found or False) as tmp:
            yield tmp
        if record:
            _record(path)
    except FileExistsError:
        raise appeared from None
    except NoSpaceError:
        raise
    except OSError as exc:
        raise InputError(f"cannot write {plain(path, 120)}: {exc.strerror or exc}") from None


def write_file(path: str | Path, writer: Callable[[Path], object]) -> None:
    """``writer(tmp)`` writes the file; it lands at ``path`` whole or not at all."""
    with written(path) as tmp:
        writer(tmp)


def write_text(path: str | Path, text: str, record: bool = True) -> None:
    """Write ``text`` (UTF-8) to ``path`` whole: a temporary file beside it, renamed into place."""
    with written(path, record) as tmp:
        tmp.write_text(text, encoding="utf-8")


def wrote(*paths: Path | str | None) -> None:
    """End a command by saying where its outputs are (on stderr, so stdout stays the result)."""
    import sys

    done = [str(p) for p in paths if p is not None]
    if done:
        print(f"rigfem: wrote {', '.join(plain(p, 200) for p in done)}", file=sys.stderr)
