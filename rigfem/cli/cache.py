"""``rigfem cache``: where rigfem's cache is, what it holds against its limit, and clearing it."""

from __future__ import annotations

import argparse
from collections import Counter

HELP = "show the cache (folder, entries by kind, size, limit) or clear it (--clear)"
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = "cache shown or cleared"


def _size(b: int) -> str:
    """Bytes in the largest unit that keeps the number at 1 or more (kB, MB, GB), 3 digits."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if b >= scale:
            return f"{b / scale:.3g} {unit}"
    return f"{b} B"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--clear", action="store_true",
                   help="remove every entry rigfem stored (folders with a manifest); nothing else is touched")


def run(args: argparse.Namespace) -> int:
    from rigfem.mesh.cache import MAX_GB_ENV, cache_dir, clear, entries, max_bytes, usable

    root, limit = cache_dir(), max_bytes()
    if args.clear:
        n, size = clear() if root.is_dir() else (0, 0)  # only rigfem's entries: a user's files stay
        print(f"cache {root}: removed {n} entries, {_size(size)}")
        return 0
    found = entries(root) if root.is_dir() else []
    count, size = Counter(), Counter()
    for folder, b, _ in found:
        kind = folder.relative_to(root).parts[0] if folder.parent != root else "other"
        count[kind] += 1
        size[kind] += b
    state = "" if usable() else " (not usable: rigfem runs without a cache)"
    print(f"cache {root}{state} (RIGFEM_CACHE)")
    for kind in sorted(count):
        print(f"  {kind}: {count[kind]} entries, {_size(size[kind])}")
    print(f"total {len(found)} entries, {_size(sum(size.values()))} of {_size(limit)} "
          f"({MAX_GB_ENV}; least recently used entries are removed past it)")
    return 0
