"""Size of the result folder of a standard check: total bytes, bytes and files per kind.

    python benchmarks/bench_folder_size.py                                   # this tree's code
    python benchmarks/bench_folder_size.py --tree before=/tmp/old after=.    # side by side

Each tree's code (``LABEL=PATH``, PATH a checkout of rigfem; default ``current=`` this repository)
runs ``python -m rigfem check SCENE --fidelity FIDELITY --out <tmp>`` in its own process
(``PYTHONPATH=PATH``, so an editable install elsewhere is not what runs), with the caller's
environment otherwise (``$RIGFEM_CACHE``: a warm cache changes the time, not the folder).  The
folder is measured file by file: total bytes, file count, bytes and count per kind (vtu, pvd,
png, html, json, md, other), the VTU bytes split into the critical-angle files and the cycle
animation's frames (``<part>_<mode>_NNN.vtu``), and every file's size.  The record is
``results/benchmarks/folder_size.json`` (benchmarks/record.py: date, commit, machine, load,
command); each sample carries its tree's commit and dirty flag, and ``derived`` the ratios of
every tree's total to the first tree's.  The wall time of each run is kept too (it includes the
solve when the cache is cold, so it is no measure of the writing alone).
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from record import ROOT, timed_process, write_record

KINDS = ("vtu", "pvd", "png", "html", "json", "md")
_FRAME = re.compile(r"_\d{3}\.vtu$")


def _tree_commit(path: Path) -> dict:
    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(path), *args], capture_output=True, text=True, check=False).stdout.strip()
    return {"sha": git("rev-parse", "HEAD"), "dirty": bool(git("status", "--porcelain", "--untracked-files=no"))}


def measure(folder: Path) -> dict:
    """Total bytes, file count, bytes and count per kind, the VTU split, every file's bytes."""
    files = {p.relative_to(folder).as_posix(): p.stat().st_size for p in sorted(folder.rglob("*")) if p.is_file()}
    out: dict = {"total_bytes": sum(files.values()), "files": len(files)}
    for kind in (*KINDS, "other"):
        sel = [n for n in files if (n.rsplit(".", 1)[-1] == kind if kind != "other"
                                    else n.rsplit(".", 1)[-1] not in KINDS)]
        out[f"{kind}_bytes"], out[f"{kind}_files"] = sum(files[n] for n in sel), len(sel)
    frames = [n for n in files if _FRAME.search(n)]
    out["vtu_frames_bytes"], out["vtu_frames_files"] = sum(files[n] for n in frames), len(frames)
    out["vtu_critical_bytes"] = out["vtu_bytes"] - out["vtu_frames_bytes"]
    out["vtu_critical_files"] = out["vtu_files"] - out["vtu_frames_files"]
    out["by_file"] = files
    return out


def run(label: str, tree: Path, scene: str, fidelity: str) -> dict:
    """One check with the code of ``tree``; its folder measured."""
    import os

    env = {**os.environ, "PYTHONPATH": str(tree)}
    with tempfile.TemporaryDirectory(prefix="rigfem-folder-size-") as tmp:
        out = Path(tmp) / "o"
        r = timed_process([sys.executable, "-m", "rigfem", "check", scene, "--fidelity", fidelity,
                           "--out", str(out), "--quiet"], env=env, cwd=tree)
        if r["exit"] not in (0, 1):
            raise SystemExit(f"{label}: rigfem check failed ({r['exit']}): {r['stderr_tail']}")
        sizes = measure(out)
    return {"label": label, "tree": str(tree), "commit": _tree_commit(tree), "exit": r["exit"],
            "wall_s": r["wall_s"], "load": r["load_before"][0], **sizes}


def _tree(arg: str) -> tuple[str, Path]:
    label, _, path = arg.partition("=")
    return label, Path(path or ROOT).resolve()


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tree", nargs="+", default=["current="], metavar="LABEL=PATH",
                    help="the code trees to measure, in order (the first is the reference of the ratios)")
    ap.add_argument("--scene", default="final-cm")
    ap.add_argument("--fidelity", default="standard")
    a = ap.parse_args(argv)
    samples = {}
    for label, tree in map(_tree, a.tree):
        s = run(label, tree, a.scene, a.fidelity)
        samples[label] = [s]
        kinds = ", ".join(f"{k} {s[f'{k}_bytes'] / 1e6:.2f} MB ({s[f'{k}_files']})" for k in (*KINDS, "other"))
        print(f"{label} ({s['commit']['sha'][:7]}{'+dirty' if s['commit']['dirty'] else ''}): "
              f"{s['total_bytes'] / 1e6:.2f} MB in {s['files']} files; {kinds}; VTU critical "
              f"{s['vtu_critical_bytes'] / 1e6:.2f} MB, frames {s['vtu_frames_bytes'] / 1e6:.2f} MB")
    ref = samples[_tree(a.tree[0])[0]][0]
    derived = {f"{label} / {ref['label']} total": rows[0]["total_bytes"] / ref["total_bytes"]
               for label, rows in samples.items()}
    derived.update({f"{label} total MB": rows[0]["total_bytes"] / 1e6 for label, rows in samples.items()})
    path = write_record("folder_size", samples, derived, {"scene": a.scene, "fidelity": a.fidelity,
                                                          "trees": a.tree})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
