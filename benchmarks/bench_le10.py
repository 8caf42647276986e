"""NAFEMS LE10 (thick plate under pressure): rigfem vs CalculiX, σyy(D), time and memory vs DOF.

Whole refinement sequence (element size ratio √2 from 400 mm to 71 mm, then 60 mm: about 400k
DOF, the largest that fits about 8 GiB — rigfem's direct solve needed 0.9 / 2.7 GiB at 83k / 207k
DOF, so about 6–7 GiB there; a 50 mm level, about 660k DOF, would switch rigfem to AMG, above
DIRECT_MAX_DOF, and is left out — run it on a quiet machine, it takes about 15 minutes):

    python benchmarks/bench_le10.py

Only the small levels (what the committed results were made with, if the table says so):

    python benchmarks/bench_le10.py --sizes 400 283 200 141

Each level is meshed once here (gmsh, OpenCASCADE, curved P2 tets: rigfem.verification.le10), then
solved in a fresh subprocess so its peak RSS is its own: rigfem (model, assembly, factorisation,
solve, stress recovery) ``--repeats`` times, then CalculiX 2.20 on the deck rigfem exports for
the identical model (same nodes, C3D10 elements, supports, consistent nodal loads), as many
times.  Times are medians of the repeats; levels above ``--single-above`` DOF run once (the
table says how many runs each figure is).  Peak RSS: VmHWM of the subprocess (rigfem) and of its
ccx children (polled every 20 ms).  Both codes run on ``--threads`` threads (1 by default).  Writes
results/benchmarks/le10.{json,png} (``python benchmarks/publish.py`` writes le10.md).
"""

from __future__ import annotations

import argparse
import os
import sys

if __name__ == "__main__":  # thread counts must be set before numpy/MKL load
    _pre = argparse.ArgumentParser(add_help=False)
    _pre.add_argument("--threads", type=int, default=1)
    _t = str(_pre.parse_known_args()[0].threads)
    os.environ.update(OMP_NUM_THREADS=_t, MKL_NUM_THREADS=_t, OPENBLAS_NUM_THREADS=_t, NUMBA_NUM_THREADS=_t)

import json
import statistics
import subprocess
import tempfile
import threading
import time
from pathlib import Path

from record import OUT, write_record

SIZES = (400.0, 283.0, 200.0, 141.0, 100.0, 71.0, 60.0)  #: mm, ratio √2, then the largest that fits


def _hwm_mib(pid: int | str = "self") -> float:
    """Peak RSS (VmHWM) of one process's own address space, MiB.  Not ``getrusage``: on Linux a child's
    ru_maxrss includes its parent's peak from before its exec."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            return next(float(line.split()[1]) / 1024 for line in fh if line.startswith("VmHWM"))
    except (OSError, StopIteration):
        return 0.0


class ChildPeak(threading.Thread):
    """Polls the VmHWM of this process's children (ccx) every ``dt`` s; ``peak`` is the largest seen."""

    def __init__(self, dt: float = 0.02) -> None:
        super().__init__(daemon=True)
        self.dt, self.peak, self._stop_event = dt, 0.0, threading.Event()

    def run(self) -> None:
        me = str(os.getpid())
        while not self._stop_event.wait(self.dt):
            for stat in Path("/proc").glob("[0-9]*/stat"):
                try:
                    if stat.read_text().rsplit(")", 1)[1].split()[1] == me:
                        self.peak = max(self.peak, _hwm_mib(stat.parent.name))
                except (OSError, IndexError):
                    continue

    def stop(self) -> float:
        self._stop_event.set()
        self.join()
        return self.peak


def solve_level(mesh_npz: str, repeats: int, single_above: int, threads: int) -> dict:
    """In a fresh process: rigfem then ccx on one LE10 mesh; times, σyy(D), peak RSS."""
    import rigfem.fe.model  # noqa: F401 - imported (with MKL/pypardiso) before the baseline RSS is read
    import rigfem.fe.solver  # noqa: F401
    from rigfem.io import export_model, run_ccx
    from rigfem.mesh.partmesh import load_npz
    from rigfem.verification.le10 import load, solve_le10, supports

    pm = load_npz(Path(mesh_npz))
    rss0 = _hwm_mib()
    rig, stages = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        r = solve_le10(pm)
        rig.append(time.perf_counter() - t0)
        stages.append(dict(r["solution"].times))
        if r["dof"] > single_above:
            break
        if len(rig) < repeats:
            del r
    rss_rig = _hwm_mib()
    with tempfile.TemporaryDirectory(prefix="le10-ccx-") as tmp:
        deck = export_model(r["model"], supports(), [load()], Path(tmp) / "le10.inp", heading="NAFEMS LE10")
        d, syy, dof, n_tets = r["node_D"], r["syy_D"], r["dof"], len(pm.tets)
        del r
        ccx, ccx_rep, syy_ccx = [], [], None
        watch = ChildPeak()
        watch.start()
        for _ in range(len(rig)):
            res = run_ccx(deck, threads=threads)
            ccx.append(res.wall_time)
            ccx_rep.append(res.ccx_time)
            syy_ccx = float(res.stress[0, d, 1])
        ccx_rss = watch.stop()
    return {"dof": dof, "tets": n_tets, "syy_D": syy, "syy_D_ccx": syy_ccx, "runs": len(rig),
            "rigfem_s": statistics.median(rig), "rigfem_all_s": rig,
            "rigfem_stages_s": {k: statistics.median(s[k] for s in stages) for k in stages[0]},
            "ccx_s": statistics.median(ccx), "ccx_all_s": ccx, "ccx_reported_s": statistics.median(ccx_rep),
            "rigfem_rss_mib": rss_rig, "rigfem_rss_base_mib": rss0,
            "ccx_rss_mib": ccx_rss}


def run(sizes, repeats: int, single_above: int, threads: int) -> list[dict]:
    """Mesh every level here, solve each in its own subprocess (:func:`solve_level`)."""
    from rigfem.mesh.partmesh import save_npz
    from rigfem.verification.le10 import TARGET_SYY, le10_mesh

    rows = []
    with tempfile.TemporaryDirectory(prefix="le10-") as tmp:
        for h in sizes:
            t0 = time.perf_counter()
            pm = le10_mesh(h)
            t_mesh = time.perf_counter() - t0
            npz, js = Path(tmp) / f"le10_{h:g}.npz", Path(tmp) / f"le10_{h:g}.json"
            save_npz(pm, npz)
            subprocess.run([sys.executable, __file__, "--threads", str(threads), "--solve", str(npz), "--json", str(js),
                            "--repeats", str(repeats), "--single-above", str(single_above)], check=True)
            row = {"size_mm": h, "layers": pm.meta["layers"], "mesh_s": t_mesh} | json.loads(js.read_text())
            row["error_pct"] = 100 * (row["syy_D"] / TARGET_SYY - 1)
            row["error_ccx_pct"] = 100 * (row["syy_D_ccx"] / TARGET_SYY - 1)
            rows.append(row)
            print(f"h {h:g} mm: {row['dof']} DOF, σyy(D) rigfem {row['syy_D']:.4f} MPa ({row['error_pct']:+.2f} %), "
                  f"ccx {row['syy_D_ccx']:.4f}; time rigfem {row['rigfem_s']:.2f} s, ccx {row['ccx_s']:.2f} s "
                  f"({row['runs']} run(s)); peak RSS rigfem {row['rigfem_rss_mib']:.0f} MiB, "
                  f"ccx {row['ccx_rss_mib']:.0f} MiB", file=sys.stderr)
    return rows


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    from rigfem.verification.le10 import TARGET_SYY

    dof = [r["dof"] for r in rows]
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    ax[0].axhspan(TARGET_SYY * 1.02, TARGET_SYY * 0.98, color="0.9", label="target ±2 %")
    ax[0].axhline(TARGET_SYY, color="k", lw=0.8, label=f"NAFEMS {TARGET_SYY} MPa")
    ax[0].plot(dof, [r["syy_D"] for r in rows], "o-", label="rigfem")
    ax[0].plot(dof, [r["syy_D_ccx"] for r in rows], "x--", label="CalculiX")
    ax[0].set(xscale="log", xlabel="degrees of freedom", ylabel="σyy at D (MPa)", title="σyy at point D vs DOF")
    ax[1].plot(dof, [r["rigfem_s"] for r in rows], "o-", label="rigfem (FE, in-process)")
    ax[1].plot(dof, [r["ccx_s"] for r in rows], "x--", label="CalculiX (ccx process)")
    ax[1].set(xscale="log", yscale="log", xlabel="degrees of freedom", ylabel="wall time (s)",
              title="Solve wall time vs DOF")
    ax[2].plot(dof, [r["rigfem_rss_mib"] for r in rows], "o-", label="rigfem")
    ax[2].plot(dof, [r["ccx_rss_mib"] for r in rows], "x--", label="CalculiX")
    ax[2].set(xscale="log", yscale="log", xlabel="degrees of freedom", ylabel="peak RSS (MiB)",
              title="Peak memory vs DOF")
    for a in ax:
        a.xaxis.set_minor_formatter(NullFormatter())
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle("NAFEMS LE10 thick plate under pressure: rigfem vs CalculiX 2.20 on the same P2 meshes")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=list(SIZES), help="element sizes, mm")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--single-above", type=int, default=300_000, help="levels above this DOF count run once")
    ap.add_argument("--threads", type=int, default=1, help="threads for both codes (MKL/OpenMP, ccx)")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--solve", help=argparse.SUPPRESS)  # internal: one level in this subprocess
    ap.add_argument("--json", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.solve:
        Path(a.json).write_text(json.dumps(solve_level(a.solve, a.repeats, a.single_above, a.threads)))
        return 0
    rows = run(a.sizes, a.repeats, a.single_above, a.threads)
    samples = {"levels": [{k: v for k, v in r.items() if not k.endswith("_all_s") and k != "rigfem_stages_s"}
                          for r in rows]}
    for r in rows:
        samples[f"{r['size_mm']:g} mm rigfem"] = [{"wall_s": t} for t in r["rigfem_all_s"]]
        samples[f"{r['size_mm']:g} mm ccx"] = [{"wall_s": t} for t in r["ccx_all_s"]]
    params = {"threads": a.threads, "single_above": a.single_above, "repeats": a.repeats, "sizes_mm": a.sizes}
    write_record("le10", samples, {"rigfem stages (s), median": {f"{r['size_mm']:g}": r["rigfem_stages_s"]
                                                                 for r in rows}}, params, out=a.out)
    plot(rows, a.out / "le10.png")
    print(f"wrote {a.out / 'le10.json'}, le10.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
