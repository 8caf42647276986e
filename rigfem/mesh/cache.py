"""Verified cache entries: whatever rigfem stores to skip a computation is checked when read.

An entry is a folder holding the files its writer made and ``manifest.json``: the SHA-256 of
every file and the full description of the inputs that produced it (parameters, and the hash
of the source files that compute it: :func:`code_hash`, so an edit invalidates entries without
a hand-bumped version).  A read verifies both; a corrupted, truncated or zeroed entry, or one
made from other inputs, is removed and logged once (``logging`` channel ``rigfem.cache``) and
the caller computes it again.  Entries are written to a temporary folder and renamed into
place, so a reader never sees half an entry.  Caches live under ``$RIGFEM_CACHE`` (default
``~/.cache/rigfem``), outside the repository.

A cache folder that is a file, cannot be written or is full is not used: rigfem runs without a
cache and says so once.  The cache holds at most ``$RIGFEM_CACHE_MAX_GB`` GB (default 5): a
read touches the entry's manifest, and after a write the least recently used entries are
removed until the cache fits.
"""

from __future__ import annotations

import functools
import hashlib
import io
import json
import logging
import os
import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from rigfem.files import file_sha256

if TYPE_CHECKING:  # numpy is imported where arrays are handled: `rigfem parts` reads volumes without it
    import numpy as np

#: the channel a discarded entry is reported on
log = logging.getLogger("rigfem.cache")
MANIFEST = "manifest.json"
#: environment variable of the cache's size limit, GB (10^9 bytes), and its default
MAX_GB_ENV, DEFAULT_MAX_GB = "RIGFEM_CACHE_MAX_GB", 5.0
#: free space below which the cache folder counts as full, bytes
MIN_FREE = 64 * 2**20


def cache_dir() -> Path:
    """Folder of rigfem's caches: $RIGFEM_CACHE or ~/.cache/rigfem (outside the repository)."""
    return Path(os.environ.get("RIGFEM_CACHE") or Path.home() / ".cache" / "rigfem")


def max_bytes() -> int:
    """The cache's size limit, bytes, from ``$RIGFEM_CACHE_MAX_GB`` (InputError if not a number > 0)."""
    from rigfem.errors import check_range

    raw = os.environ.get(MAX_GB_ENV) or DEFAULT_MAX_GB
    return int(check_range(MAX_GB_ENV, raw, 0.0, 1e6, "GB", lo_open=True) * 1e9)


def usable() -> bool:
    """Whether the cache folder can be used; if not, why is logged once (rigfem runs without it)."""
    return _usable(str(cache_dir()))


@functools.lru_cache(maxsize=None)
def _usable(path: str) -> bool:
    root = Path(path)
    why = ""
    if root.exists() and not root.is_dir():
        why = "it is a file"
    else:
        try:
            root.mkdir(parents=True, exist_ok=True)
            fd, probe = tempfile.mkstemp(prefix=".probe-", dir=root)
            os.close(fd)
            os.unlink(probe)
            if shutil.disk_usage(root).free < MIN_FREE:
                why = f"less than {MIN_FREE // 2**20} MiB free"
        except OSError as exc:
            why = f"cannot write there: {exc.strerror or type(exc).__name__}"
    if why:
        log.warning("cache folder %s (RIGFEM_CACHE) not usable (%s); running without a cache", path, why)
    return not why


def _in_cache(folder: Path) -> bool:
    return Path(folder).is_relative_to(cache_dir())


def entries(root: Path | None = None) -> list[tuple[Path, int, float]]:
    """Every entry under the cache folder: (folder, bytes, last use as a timestamp), oldest first."""
    out = []
    for man in Path(root or cache_dir()).rglob(MANIFEST):
        try:
            files = [f for f in man.parent.iterdir() if f.is_file()]
            out.append((man.parent, sum(f.stat().st_size for f in files), man.stat().st_mtime))
        except OSError:
            continue
    return sorted(out, key=lambda e: e[2])


def evict(keep: Path | None = None) -> list[Path]:
    """Remove the least recently used entries until the cache fits :func:`max_bytes`; never ``keep``."""
    limit, found = max_bytes(), entries()
    total, removed = sum(e[1] for e in found), []
    for folder, size, _ in found:
        if total <= limit:
            break
        if folder != keep:
            shutil.rmtree(folder, ignore_errors=True)
            total -= size
            removed.append(folder)
    _tally[str(cache_dir())] = [total, time.monotonic()]
    return removed


#: seconds after which a write scans the whole cache again, though this process's tally fits
RESCAN_S = 60.0
#: per cache folder: [its bytes at the last scan plus what this process stored since, time of that scan]
_tally: dict[str, list] = {}


def _stored(folder: Path, size: int) -> None:
    """Account for an entry of ``size`` bytes just stored: scan and evict (:func:`evict`) only when
    this process's tally would pass the limit, or its last scan is :data:`RESCAN_S` old (other
    processes write too), not on every write (a scan reads every manifest: quadratic in a sweep)."""
    t = _tally.get(str(cache_dir()))
    if t is None or t[0] + size > max_bytes() or time.monotonic() - t[1] > RESCAN_S:
        evict(keep=folder)
    else:
        t[0] += size


def clear() -> tuple[int, int]:
    """Remove every entry rigfem made under the cache folder (folders with a manifest), and the
    kind folders left empty; anything else stays.  Returns (entries, bytes) removed."""
    found = entries()
    _tally.pop(str(cache_dir()), None)
    for folder, _, _ in found:
        shutil.rmtree(folder, ignore_errors=True)
    for kind in {f.parent for f, _, _ in found}:
        try:
            kind.rmdir()
        except OSError:
            pass
    return len(found), sum(e[1] for e in found)


@functools.lru_cache(maxsize=None)
def code_hash(*patterns: str) -> str:
    """SHA-256 (16 hex digits) of the rigfem source files matching ``patterns`` (globs relative
    to the package, e.g. ``"mesh/*.py"``): the code that computes an entry is part of its key."""
    root = Path(__file__).resolve().parents[1]
    files = sorted({f for p in patterns for f in root.glob(p)})
    if not files:
        raise ValueError(f"code_hash: no source file matches {patterns}")
    h = hashlib.sha256()
    for f in files:
        h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:16]


def _canonical(inputs: dict) -> dict:
    return json.loads(json.dumps(inputs, sort_keys=True, default=str))


def entry_key(inputs: dict) -> str:
    """The key (32 hex digits) of an entry: a hash of its full input description."""
    return hashlib.sha256(json.dumps(_canonical(inputs), sort_keys=True).encode()).hexdigest()[:32]


def array_digest(*arrays) -> str:
    """SHA-256 of arrays (dtype, shape and bytes): an input key's stand-in for large arrays."""
    import numpy as np

    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.data)
    return h.hexdigest()


def discard(folder: Path, why: str) -> None:
    """Remove a bad entry and say so once; the caller computes it again."""
    log.warning("cache entry %s discarded (%s); computing it again", folder, why)
    shutil.rmtree(folder, ignore_errors=True)


def read_entry(folder: Path, inputs: dict) -> Path | None:
    """``folder`` if it holds a verified entry of ``inputs``; None if it is missing or was bad
    (then it is removed and logged).  A hit under the cache folder marks the entry as used."""
    return folder if _verified(folder, inputs, (), {}) else None


def read_arrays(folder: Path, inputs: dict, names: tuple[str, ...]) -> dict[str, np.ndarray] | None:
    """The arrays ``names`` (:func:`save_arrays`) of a verified entry of ``inputs``, or None as
    :func:`read_entry`.  Each array's file is read once: its checksum is taken on the very bytes
    the array is made from (for the hundreds of MB of a part's unit solutions, half the reading)."""
    got: dict[str, np.ndarray] = {}
    return got if _verified(folder, inputs, names, got) else None


def _verified(folder: Path, inputs: dict, names: tuple[str, ...], got: dict) -> bool:
    if _in_cache(folder) and not usable() or not folder.exists():
        return False
    why = _why_bad(folder, inputs, {f"{n}.npy": n for n in names}, got)
    if why:
        discard(folder, why)
        return False
    if _in_cache(folder):
        try:
            os.utime(folder / MANIFEST)  # least recently used goes first
        except OSError:
            pass
    return True


def _why_bad(folder: Path, inputs: dict, arrays: dict[str, str], got: dict) -> str:
    """Why an entry cannot be used ("" if it can); the files named in ``arrays`` are read into ``got``."""
    try:
        man = json.loads((folder / MANIFEST).read_text())
        files = man["files"]
        if man["inputs"] != _canonical(inputs):
            return "made from other inputs"
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as e:
        return f"unreadable manifest: {type(e).__name__}"
    try:
        present = {p.name for p in folder.iterdir()} - {MANIFEST}
        if present != set(files) or not set(arrays) <= present:
            return f"files {sorted((present ^ set(files)) | (set(arrays) - present))} missing or unexpected"
        for name, digest in files.items():
            if name in arrays:
                buf = _whole(folder / name)
                if hashlib.sha256(buf).hexdigest() != digest:
                    return f"{name} does not match its checksum"
                got[arrays[name]] = _npy(buf)
            elif file_sha256(folder / name) != digest:
                return f"{name} does not match its checksum"
    except (OSError, ValueError, TypeError) as e:
        return f"unreadable: {type(e).__name__}"
    return ""


def _whole(path: Path) -> bytearray:
    """A file's bytes, read into one buffer (no copy made later: arrays are views of it).  A
    bytearray, not ``np.empty``: numpy's huge-page advice on a large buffer made the read slower."""
    buf = bytearray(path.stat().st_size)
    with open(path, "rb", buffering=0) as fh:
        view, n = memoryview(buf), 0
        while n < len(buf):
            k = fh.readinto(view[n:])
            if not k:
                raise ValueError(f"{path.name} shorter than its size")
            n += k
    return buf


def _npy(buf: bytearray) -> np.ndarray:
    """The array of a ``.npy`` file's bytes, a view of ``buf`` (no pickles: object arrays refused)."""
    import numpy as np

    head = io.BytesIO(bytes(buf[:1 << 16]))
    version = np.lib.format.read_magic(head)
    read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
    shape, fortran, dtype = read(head)
    if dtype.hasobject:
        raise ValueError("object arrays are not read")
    count = int(np.prod(shape, dtype=np.int64))
    a = np.frombuffer(buf, dtype=dtype, count=count, offset=head.tell())
    return a.reshape(shape, order="F" if fortran else "C")


def write_entry(folder: Path, inputs: dict, write: Callable[[Path], None]) -> bool:
    """Store an entry: ``write(tmp)`` makes its files in a temporary folder, the manifest is
    added, and the folder is renamed to ``folder``.  False if it could not be stored (a full
    disk, an unusable cache folder, or a concurrent writer got there first): a cache is an
    optimisation only.  Under the cache folder, older entries are then evicted to fit its limit."""
    cached = _in_cache(folder)
    if cached and not usable():
        return False
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}-", dir=folder.parent))
    except OSError:
        return False
    try:
        write(tmp)
        files = {p.name: file_sha256(p) for p in sorted(tmp.iterdir())}
        (tmp / MANIFEST).write_text(json.dumps({"inputs": _canonical(inputs), "files": files}))
        size = sum(p.stat().st_size for p in tmp.iterdir())
        os.replace(tmp, folder)
    except OSError:
        shutil.rmtree(tmp, ignore_errors=True)
        return False
    except BaseException:  # interrupted: no half entry left behind
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if cached:
        _stored(folder, size)
    return True


def save_arrays(folder: Path, arrays: dict[str, np.ndarray]) -> None:
    """Write each array as ``<name>.npy`` in ``folder`` (for :func:`write_entry`)."""
    import numpy as np

    for name, a in arrays.items():
        np.save(folder / f"{name}.npy", np.asarray(a), allow_pickle=False)


def cached_arrays(kind: str, inputs: dict, names: tuple[str, ...], compute: Callable[[], dict[str, np.ndarray]],
                  check: Callable[[dict[str, np.ndarray]], str]) -> tuple[dict[str, np.ndarray], bool]:
    """The arrays ``names`` that ``compute()`` returns, through the verified entry
    ``cache_dir()/kind/<key of inputs>``, and whether they were read from it.  A stored entry is
    used only if ``check(arrays)`` returns "" (else the reason: it is discarded and computed again)."""
    folder = cache_dir() / kind / entry_key(inputs)
    got = read_arrays(folder, inputs, names)
    if got is not None:
        try:
            why = check(got)
        except (ValueError, KeyError, IndexError, TypeError) as e:
            why = f"unreadable: {type(e).__name__}"
        if not why:
            return got, True
        discard(folder, why)
    arrays = compute()
    write_entry(folder, inputs, lambda tmp: save_arrays(tmp, arrays))
    return arrays, False

