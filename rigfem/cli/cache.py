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
                   help="remove every entry rigfem stored (signed, under its own subfolder); nothing else is touched")


def run(args: argparse.Namespace) -> int:
    from rigfem.cache import CACHE_ENV, DEFAULT_GB, ENTRIES, MAX_GB_ENV, from_environment

    cache = from_environment()
    if cache.root is None:
        print(f"no usable cache folder ({CACHE_ENV}): rigfem runs without a cache")
        return 0
    if args.clear:
        n, size = cache.clear()  # only rigfem's entries: nothing else in the folder is touched
        print(f"cache {cache.root}: removed {n} entries, {_size(size)}")
        return 0
    found = cache.entries()
    count, size = Counter(), Counter()
    for folder, b, _ in found:
        count[folder.parent.name] += 1
        size[folder.parent.name] += b
    print(f"cache {cache.root} ({CACHE_ENV}; rigfem's entries under {ENTRIES}/)")
    for kind in sorted(count):
        print(f"  {kind}: {count[kind]} entries, {_size(size[kind])}")
    print(f"total {len(found)} entries, {_size(sum(size.values()))} of {_size(cache.max_bytes)} "
          f"({MAX_GB_ENV}, default a quarter of the free disk within {DEFAULT_GB[0]:g}-{DEFAULT_GB[1]:g} GB; "
          f"least recently used entries are removed past it)")
    return 0
