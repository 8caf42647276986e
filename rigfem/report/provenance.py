"""Where a result came from: rigfem's version and commit, the date, Python and the key libraries,
the machine, and the hashes of what was checked.  Never fails: what cannot be read says so.

The commit is read from git when rigfem runs from a checkout (``dirty``: what ran, the package,
its part files (geometry/) or pyproject.toml, differs from it; a changed result or page elsewhere in
the checkout does not change what ran); an installed package says ``not a checkout``.
"""

from __future__ import annotations

import datetime
import functools
import os
import platform
import subprocess
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from rigfem import __version__

__all__ = ["LIBRARIES", "build", "provenance"]

#: distributions whose versions a result records (the FE, the mesher, the direct solver and its MKL)
LIBRARIES = ("numpy", "scipy", "scikit-fem", "gmsh", "pypardiso", "mkl", "matplotlib")


def _git(root: Path, *args: str) -> str | None:
    """``git -C root args`` stdout, or None when git is missing, fails or hangs."""
    try:
        out = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, timeout=10,
                             stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


#: what runs, relative to the checkout: its changes (untracked files included) make a result dirty
CODE = ("rigfem", "geometry", "pyproject.toml")


def _commit(root: Path = Path(__file__).resolve().parents[2]) -> tuple[str, bool | None]:
    """(commit, dirty) of the checkout rigfem runs from; ('not a checkout', None) otherwise."""
    if not (root / ".git").exists() or not (root / "pyproject.toml").is_file():
        return "not a checkout", None
    head = _git(root, "rev-parse", "HEAD")
    if not head:
        return "unknown (git could not read the checkout)", None
    status = _git(root, "status", "--porcelain", "--untracked-files=normal", "--", *CODE)
    return head, None if status is None else bool(status)


def _version(dist: str) -> str:
    try:
        return version(dist)
    except PackageNotFoundError:
        return "not installed"


def _cpu() -> str:
    """The processor's model name (Linux), else what platform says."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


@functools.lru_cache(maxsize=1)
def build() -> dict:
    """What this process runs: rigfem (version, commit, dirty), Python, the key libraries, the machine."""
    commit, dirty = _commit()
    return {"rigfem_version": __version__, "commit": commit, "dirty": dirty,
            "python": platform.python_version(), "libraries": {d: _version(d) for d in LIBRARIES},
            "machine": {"host": platform.node(), "system": platform.platform(), "cpu": _cpu(),
                        "cores": os.cpu_count() or 0}}


def provenance(scene_sha256: str, input_sha256: str, author: str = "") -> dict:
    """The provenance block of a report: :func:`build`, the date (UTC), the hashes and the author."""
    now = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)
    return {**build(), "date_utc": now.isoformat().replace("+00:00", "Z"), "scene_sha256": scene_sha256,
            "input_sha256": input_sha256, "author": author}
