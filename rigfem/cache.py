"""The one cache: whatever rigfem stores to skip a computation, verified when read.

An entry is a folder ``<root>/rigfem-entries/<kind>/<key>/`` holding the files its writer made and
``manifest.json``: rigfem's signature, the kind, the full description of the inputs (an array in
them by its digest, :func:`array_digest`), rigfem's
version, a hash of the whole installed package (:func:`package_hash`: any edit of any file of it
invalidates every entry, no hand-kept list of source files) and the SHA-256 of every file.  A read
verifies all of it; an entry that is corrupt, truncated, made from other inputs or by another
package, or that vanished while it was read (another process cleared it), is computed again,
never fatal.  Entries are written to a temporary folder and renamed into place, so a reader never
sees half an entry.

rigfem removes only what it can prove it wrote: folders under its own subfolder whose manifest
carries its signature and that hold nothing but the files the manifest lists; never the root,
never anything else in it (``$RIGFEM_CACHE=~/.cache`` is safe).  The cache holds at most
``max_bytes``: a read marks the entry as used, and a write past the limit removes the least
recently used entries.

Where the cache is comes from the caller: :func:`from_environment` reads ``$RIGFEM_CACHE``
(default ``~/.cache/rigfem``) and ``$RIGFEM_CACHE_MAX_GB`` once, at the edge (the CLI, or a
library call given no cache), and the :class:`Cache` value travels from there.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import io
import json
import logging
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from rigfem import __version__
from rigfem.errors import check_range, plain
from rigfem.files import file_sha256

if TYPE_CHECKING:  # numpy is imported where arrays are handled: `rigfem parts` reads volumes without it
    import numpy as np

T = TypeVar("T")

__all__ = ["Cache", "NO_CACHE", "from_environment", "package_hash", "array_digest", "Entry", "save_arrays",
           "CACHE_ENV", "MAX_GB_ENV", "resolve", "environment_root"]

#: the channel a discarded entry or an unusable cache folder is reported on
log = logging.getLogger("rigfem.cache")
#: environment variables of the cache's folder and size limit (GB, 10^9 bytes)
CACHE_ENV, MAX_GB_ENV = "RIGFEM_CACHE", "RIGFEM_CACHE_MAX_GB"
#: rigfem's own subfolder of the cache root: everything it writes lives under it
ENTRIES = "rigfem-entries"
MANIFEST = "manifest.json"
#: what every manifest rigfem writes says of its writer (an entry without it is not rigfem's)
SIGNATURE = {"writer": "rigfem", "format": 2}
#: free space below which the cache folder counts as full, bytes
MIN_FREE = 64 * 2**20
#: the default size limit: a quarter of the cache disk's free space, within these bounds (GB) — a
#: check adds about 0.3 GB, a sweep's or a synthesis's unit bases 1-3 GB (docs: the cache)
DEFAULT_GB = (5.0, 50.0)


@functools.lru_cache(maxsize=1)
def package_hash() -> str:
    """SHA-256 (16 hex digits) of every file of the installed rigfem package (code, templates,
    scenes, part files): the code that computed an entry is part of its key."""
    root = Path(__file__).resolve().parent
    files = []
    for folder, dirs, names in os.walk(root, followlinks=True):  # rigfem/geometry is a link in the source tree
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        files += [Path(folder, n) for n in names if not n.endswith((".pyc", ".pyo"))]
    h = hashlib.sha256()
    for f in sorted(files, key=lambda f: f.relative_to(root).as_posix()):
        h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()[:16]


def array_digest(*arrays) -> str:
    """SHA-256 of arrays (dtype, shape and bytes): an input's stand-in for large arrays."""
    import numpy as np

    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.data)
    return h.hexdigest()


def _encoded(value: Any) -> Any:
    """A key's stand-in for what JSON cannot hold: a numpy scalar by its value, an array by its digest
    (:func:`array_digest`; never one of objects, whose bytes are addresses), anything else by its text."""
    if type(value).__module__ == "numpy" and hasattr(value, "dtype"):  # numpy's own: not imported for it
        if value.dtype.hasobject:
            raise TypeError("an array of Python objects cannot key a cache entry")
        return value.item() if value.ndim == 0 else {"array": array_digest(value)}
    return str(value)


def _canonical(inputs: Mapping) -> dict:
    """``inputs`` as the key holds them: plain JSON, arrays by their digest."""
    return json.loads(json.dumps(inputs, sort_keys=True, default=_encoded))


class Corrupt(ValueError):
    """An entry's file does not match its manifest."""


class Entry:
    """A verified entry's files, each checked against its SHA-256 as it is read."""

    def __init__(self, folder: Path, files: dict[str, str]) -> None:
        self.folder, self.files, self._checked = folder, files, set()

    def bytes(self, name: str) -> bytearray:
        """A file's bytes, read once into one buffer and checked (arrays are views of it)."""
        path = self.folder / name
        buf = bytearray(path.stat().st_size)
        with open(path, "rb", buffering=0) as fh:
            view, n = memoryview(buf), 0
            while n < len(buf):
                k = fh.readinto(view[n:])
                if not k:
                    raise Corrupt(f"{name} shorter than its size")
                n += k
        if hashlib.sha256(buf).hexdigest() != self.files.get(name):
            raise Corrupt(f"{name} does not match its checksum")
        self._checked.add(name)
        return buf

    def text(self, name: str) -> str:
        return self.bytes(name).decode()

    def json(self, name: str) -> Any:
        return json.loads(self.text(name))

    def array(self, name: str) -> np.ndarray:
        """The array of ``<name>.npy`` (:func:`save_arrays`), a view of its checked bytes (no pickles)."""
        import numpy as np

        buf = self.bytes(f"{name}.npy")
        head = io.BytesIO(bytes(buf[:1 << 16]))
        version = np.lib.format.read_magic(head)
        read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = read(head)
        if dtype.hasobject:
            raise Corrupt("object arrays are not read")
        count = int(np.prod(shape, dtype=np.int64))
        a = np.frombuffer(buf, dtype=dtype, count=count, offset=head.tell())
        return a.reshape(shape, order="F" if fortran else "C")

    def copy(self, name: str, dest: Path) -> None:
        """Copy a file to ``dest``, checked as it streams (a basis's fields are gigabytes)."""
        h = hashlib.sha256()
        try:
            with open(self.folder / name, "rb") as src, open(dest, "wb") as out:
                for block in iter(lambda: src.read(1 << 22), b""):
                    h.update(block)
                    out.write(block)
            if h.hexdigest() != self.files.get(name):
                raise Corrupt(f"{name} does not match its checksum")
        except BaseException:
            dest.unlink(missing_ok=True)
            raise
        self._checked.add(name)

    def rest(self) -> None:
        """Check the files nobody read."""
        for name, digest in self.files.items():
            if name not in self._checked and file_sha256(self.folder / name) != digest:
                raise Corrupt(f"{name} does not match its checksum")


def save_arrays(folder: Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Write each array as ``<name>.npy`` in ``folder`` (a ``save`` of :meth:`Cache.cached`)."""
    import numpy as np

    for name, a in arrays.items():
        np.save(folder / f"{name}.npy", np.asarray(a), allow_pickle=False)


@dataclasses.dataclass(frozen=True)
class Cache:
    """A cache folder and its size limit; ``root=None`` is no cache (everything is computed).

    ``off`` names kinds this cache does not keep (benchmarks/bench_cache.py measures each kind)."""

    root: Path | None = None
    max_bytes: int = 0
    off: frozenset[str] = frozenset()

    @property
    def folder(self) -> Path | None:
        """rigfem's own subfolder of the root, or None."""
        return None if self.root is None else Path(self.root) / ENTRIES

    def without(self, *kinds: str) -> Cache:
        """The same cache, not keeping ``kinds``."""
        return dataclasses.replace(self, off=self.off | frozenset(kinds))

    def entry_folder(self, kind: str, inputs: Mapping) -> Path | None:
        """Where the entry of ``kind`` and ``inputs`` lives, or None (no cache, or the kind is off)."""
        if self.folder is None or kind in self.off:
            return None
        key = {"kind": kind, "inputs": _canonical(inputs), "rigfem": __version__, "package": package_hash()}
        return self.folder / kind / hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:32]

    def has(self, kind: str, inputs: Mapping) -> bool:
        """Whether an entry seems stored (a cheap look, nothing verified)."""
        folder = self.entry_folder(kind, inputs)
        return folder is not None and (folder / MANIFEST).is_file()

    def get(self, kind: str, inputs: Mapping, load: Callable[[Entry], T],
            check: Callable[[T], str] | None = None) -> T | None:
        """``load(entry)`` of the verified entry of ``inputs``, or None: missing, vanished while it
        was read, or bad (then it is removed and logged; the caller computes it again).  ``check``
        returns why a loaded value cannot be right ("" if it can)."""
        inputs = _canonical(inputs)  # arrays hashed once, not for the key and again for the manifest
        folder = self.entry_folder(kind, inputs)
        if folder is None or not (folder / MANIFEST).is_file():
            return None
        try:
            man = json.loads((folder / MANIFEST).read_text())
            why = _why_foreign(man, kind, inputs)
            if not why:
                entry = Entry(folder, man["files"])
                present = {p.name for p in folder.iterdir()} - {MANIFEST}
                if present != set(entry.files):
                    why = f"files {sorted(present ^ set(entry.files))} missing or unexpected"
                else:
                    value = load(entry)
                    entry.rest()
                    why = check(value) if check else ""
        except FileNotFoundError:  # cleared or evicted by another process while it was read
            return None
        except (OSError, ValueError, KeyError, TypeError, AttributeError, IndexError) as exc:
            why = f"unreadable: {type(exc).__name__}: {exc}"
        if why:
            _discard(folder, why)
            return None
        try:
            os.utime(folder / MANIFEST)  # least recently used goes first
        except OSError:
            pass
        return value

    def put(self, kind: str, inputs: Mapping, save: Callable[[Path], None]) -> bool:
        """Store an entry: ``save(tmp)`` writes its files in a temporary folder, the manifest is
        added and the folder renamed into place.  False if it could not be stored (no cache, a full
        disk, a concurrent writer got there first): a cache is an optimisation only."""
        inputs = _canonical(inputs)
        folder = self.entry_folder(kind, inputs)
        if folder is None:
            return False
        try:
            folder.parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(prefix=".w-", dir=folder.parent))
        except OSError:
            return False
        try:
            save(tmp)
            files = {p.name: file_sha256(p) for p in sorted(tmp.iterdir())}
            man = {**SIGNATURE, "kind": kind, "inputs": inputs, "rigfem": __version__,
                   "package": package_hash(), "files": files}
            (tmp / MANIFEST).write_text(json.dumps(man))
            size = sum(p.stat().st_size for p in tmp.iterdir())
            os.replace(tmp, folder)
        except OSError:
            shutil.rmtree(tmp, ignore_errors=True)
            return False
        except BaseException:  # interrupted, or the writer failed: no half entry left behind
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        self._stored(folder, size)
        return True

    def cached(self, kind: str, inputs: Mapping, compute: Callable[[], T], save: Callable[[T, Path], None],
               load: Callable[[Entry], T], check: Callable[[T], str] | None = None) -> tuple[T, bool]:
        """``compute()``, or the stored value of ``inputs``; and whether it was stored.  A new
        value is saved with ``save(value, folder)``; a stored one read with ``load(entry)`` and
        used only if ``check(value)`` says nothing against it."""
        inputs = _canonical(inputs)
        got = self.get(kind, inputs, load, check)
        if got is not None:
            return got, True
        value = compute()
        self.put(kind, inputs, lambda tmp: save(value, tmp))
        return value, False

    # ---------------------------------------------------------------------- what is stored
    def entries(self) -> list[tuple[Path, int, float]]:
        """Every entry rigfem wrote here (signed manifest, nothing but its files): (folder, bytes,
        last use as a timestamp), oldest first."""
        out = []
        if self.folder is None or not self.folder.is_dir():
            return out
        for man in self.folder.glob(f"*/*/{MANIFEST}"):
            try:
                files = json.loads(man.read_text()).get("files") if _signed(man) else None
                present = [p for p in man.parent.iterdir() if p.name != MANIFEST]
                if not isinstance(files, dict) or {p.name for p in present} != set(files):
                    continue  # not rigfem's, or holds something else: never removed
                if any(not p.is_file() or p.is_symlink() for p in present):
                    continue
                out.append((man.parent, sum(p.stat().st_size for p in present), man.stat().st_mtime))
            except (OSError, ValueError, AttributeError):
                continue
        return sorted(out, key=lambda e: e[2])

    def evict(self, keep: Path | None = None) -> list[Path]:
        """Remove the least recently used entries until the cache fits ``max_bytes``; never ``keep``."""
        found = self.entries()
        total, removed = sum(e[1] for e in found), []
        for folder, size, _ in found:
            if total <= self.max_bytes:
                break
            if folder != keep:
                _remove(folder)
                total -= size
                removed.append(folder)
        _tally[str(self.folder)] = [total, time.monotonic()]
        return removed

    def clear(self) -> tuple[int, int]:
        """Remove every entry rigfem wrote, and the kind folders (and its own subfolder) left
        empty; anything else stays.  Returns (entries, bytes) removed."""
        found = self.entries()
        _tally.pop(str(self.folder), None)
        for folder, _, _ in found:
            _remove(folder)
        for kind in {f.parent for f, _, _ in found}:
            try:
                kind.rmdir()
            except OSError:  # holds something else
                pass
        try:
            if self.folder is not None:
                self.folder.rmdir()
        except OSError:
            pass
        return len(found), sum(e[1] for e in found)

    def _stored(self, folder: Path, size: int) -> None:
        """Account for an entry just stored: scan and evict only when this process's tally would
        pass the limit, or its last scan is :data:`RESCAN_S` old (other processes write too)."""
        t = _tally.get(str(self.folder))
        if t is None or t[0] + size > self.max_bytes or time.monotonic() - t[1] > RESCAN_S:
            self.evict(keep=folder)
        else:
            t[0] += size


#: no cache: everything is computed
NO_CACHE = Cache()
#: seconds after which a write scans the whole cache again, though this process's tally fits
RESCAN_S = 60.0
#: per cache folder: [its bytes at the last scan plus what this process stored since, time of that scan]
_tally: dict[str, list] = {}


def _signed(man: Path) -> bool:
    try:
        data = json.loads(man.read_text())
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and all(data.get(k) == v for k, v in SIGNATURE.items())


def _why_foreign(man: dict, kind: str, inputs: Mapping) -> str:
    if not isinstance(man, dict) or any(man.get(k) != v for k, v in SIGNATURE.items()):
        return "not written by this rigfem"
    if man.get("kind") != kind or man.get("inputs") != _canonical(inputs):
        return "made from other inputs"
    if man.get("package") != package_hash() or man.get("rigfem") != __version__:
        return "made by another rigfem"
    return "" if isinstance(man.get("files"), dict) else "no file list"


def _remove(folder: Path) -> None:
    """Remove an entry: renamed away first, so no reader sees it half-removed."""
    gone = folder.with_name(f".rm-{folder.name}-{os.getpid()}")
    try:
        os.rename(folder, gone)
    except OSError:
        return
    shutil.rmtree(gone, ignore_errors=True)


def _discard(folder: Path, why: str) -> None:
    log.warning("cache entry %s discarded (%s); computing it again", folder, why)
    _remove(folder)


def resolve(cache: Cache | None) -> Cache:
    """``cache``, or the environment's (:func:`from_environment`) when None: a library call given
    no cache uses the one the command line would."""
    return from_environment() if cache is None else cache


def _nearest(p: Path) -> Path:
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def environment_root(env: Mapping[str, str] | None = None) -> Path:
    """The cache folder ``$RIGFEM_CACHE`` names (default ``~/.cache/rigfem``), absolute, untouched."""
    env = os.environ if env is None else env
    return Path(env.get(CACHE_ENV) or Path.home() / ".cache" / "rigfem").expanduser().absolute()


def from_environment(env: Mapping[str, str] | None = None) -> Cache:
    """The cache ``$RIGFEM_CACHE`` (default ``~/.cache/rigfem``) names, limited to
    ``$RIGFEM_CACHE_MAX_GB`` (default: :data:`DEFAULT_GB`): InputError naming the variable when the
    limit is not a number in (0, 10^6]; no cache (said once on the log) when the folder is a file,
    cannot be written or its disk is full."""
    env = os.environ if env is None else env
    raw = env.get(MAX_GB_ENV, "")
    limit_gb = check_range(MAX_GB_ENV, raw, 0.0, 1e6, "GB", lo_open=True) if raw.strip() else None
    return _environment(str(environment_root(env)), limit_gb)


@functools.lru_cache(maxsize=8)
def _environment(root: str, limit_gb: float | None) -> Cache:
    path = Path(root)
    why = ""
    if path.exists() and not path.is_dir():
        why = "it is a file"
    else:
        try:
            (path / ENTRIES).mkdir(parents=True, exist_ok=True)
            fd, probe = tempfile.mkstemp(prefix=".probe-", dir=path / ENTRIES)
            os.close(fd)
            os.unlink(probe)
            if shutil.disk_usage(path).free < MIN_FREE:
                why = f"less than {MIN_FREE // 2**20} MiB free"
        except OSError as exc:
            why = f"cannot write there: {plain(exc.strerror or type(exc).__name__, 80)}"
    if why:
        log.warning("cache folder %s (%s) not usable (%s); running without a cache", root, CACHE_ENV, why)
        return NO_CACHE
    if limit_gb is None:  # as the cache grows the disk's free space shrinks: it settles at a fifth of it
        lo, hi = DEFAULT_GB
        limit_gb = min(max(0.25 * shutil.disk_usage(_nearest(path)).free / 1e9, lo), hi)
    return Cache(path, int(limit_gb * 1e9))
