"""Give the heap's free memory back to the system (glibc's ``malloc_trim``).

A part's solve frees hundreds of MB of arrays; glibc keeps much of it (arrays below its adaptive
mmap threshold come from the heap, and a fragmented heap does not shrink), so a process that
solves part after part would hold the largest part's memory for the rest of its run.  Trimming
once a part is done costs milliseconds; fixing the mmap threshold instead would map and unmap
every large temporary afresh (benchmarks/bench_malloc_trim.py).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools

__all__ = ["trim_heap"]


@functools.lru_cache(maxsize=1)
def _libc():
    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name) if name else None
        return libc if libc is not None and hasattr(libc, "malloc_trim") else None
    except OSError:
        return None


def trim_heap() -> None:
    """Return the heap's free pages to the system where the C library can (glibc); else nothing."""
    libc = _libc()
    if libc is not None:
        libc.malloc_trim(0)
