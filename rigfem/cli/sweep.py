"""``rigfem sweep``: every rig configuration → assembles, rig rules, reactions, part utilisation, verdict."""

from __future__ import annotations

import argparse
import os
import sys

HELP = "sweep every four-bar or slider-crank configuration of the rig (table, maps, worst list)"
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = "sweep written (a configuration that fails is a row of the table, not an exit code)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from rigfem.settings import MODELS
    from rigfem.settings import FIDELITY

    kind = p.add_mutually_exclusive_group()
    kind.add_argument("--four-bar", dest="linkage", action="store_const", const="four-bar",
                      help="sweep the four-bar (default)")
    kind.add_argument("--slider-crank", dest="linkage", action="store_const", const="slider-crank",
                      help="sweep the slider-crank")
    p.add_argument("--speed-hz", type=float, default=1.0, help="crank speed, Hz (default 1)")
    p.add_argument("--model", choices=MODELS, default="rigid-body", help="dynamics model (default rigid-body)")
    p.add_argument("--fidelity", choices=list(FIDELITY), default="draft", help="FE mesh preset (default draft)")
    p.add_argument("--samples", type=int, default=360, help="crank angles per turn (default 360)")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                   help="run on an existing Dask cluster, port 1-65535, contacted within 5 s before any work "
                        "(unreachable: exit 3; default: a local cluster in this process)")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                   help="local Dask worker processes (default: CPU count; 1 = serial, no cluster)")
    p.add_argument("--chunk-size", type=int, default=64, help="configurations per stored chunk (default 64)")
    p.add_argument("--out", default="results/sweep", help="output folder: a new one, or with --force one rigfem "
                                                          "wrote (finished chunks are reused from the cache)")
    p.add_argument("--force", action="store_true", help="write into an existing --out folder rigfem wrote")
    p.add_argument("--quiet", action="store_true", help="no progress bar or progress lines")
    p.add_argument("--report-only", action="store_true",
                   help="rewrite the maps, worst list, HTML pages and explorer from the folder's table (no sweep)")


def run(args: argparse.Namespace) -> int:
    from rigfem.cli.outputs import mark_folder, new_folder, write_text, wrote
    from rigfem.cli.progress import OBSERVER
    from rigfem.errors import InputError, check_range
    from rigfem.sweep.configs import SweepParams

    if args.scheduler is not None:
        from rigfem.sweep.run import check_scheduler

        check_scheduler(args.scheduler)  # bad input before anything; run_sweep connects before any work
    p = SweepParams(linkage_type=args.linkage or "four-bar", speed_hz=args.speed_hz, model=args.model,
                    fidelity=args.fidelity, samples=args.samples)
    out = new_folder("--out", args.out, args.force)   # before the heavy imports and any computation
    check_range("--workers", args.workers, 1, 256)
    check_range("--chunk-size", args.chunk_size, 1, 100_000)
    if not args.report_only:
        from rigfem.mesh.mesher import MACHINE_GIB
        from rigfem.sweep.cost import check_cost, sweep_cost
        from rigfem.sweep.configs import enumerate_configs

        configs = enumerate_configs(p)
        check_cost(sweep_cost(p, configs, args.workers), MACHINE_GIB)  # before the folder is made
        if args.scheduler is not None:
            from rigfem.sweep.run import reach_scheduler

            reach_scheduler(args.scheduler)  # a Dask scheduler answers there, in seconds
    from rigfem.sweep.run import run_sweep
    from rigfem.sweep.report import write_report

    if args.report_only:
        import pandas as pd

        csv = out / f"sweep_{p.linkage_type}.csv.gz"
        if not csv.is_file():
            raise InputError(f"--out = {str(out)!r} has no {csv.name}: run the sweep first (without --report-only)")
        files = write_report(pd.read_csv(csv), p, out)
        print(f"{p.linkage_type}: wrote {', '.join(str(out / f) for f in files)}")
        wrote(out)
        return 0
    mark_folder(out)
    from rigfem.cache import Cache, from_environment

    # finished chunks are verified cache entries: any later run of this sweep (into any folder)
    # reads them instead of computing them (in --out/.work only when the cache cannot be used)
    cache = from_environment()
    if cache.folder is None:
        cache = Cache(out / ".work", 1 << 62)
        write_text(out / ".work" / ".gitignore", "*\n", record=False)  # never in a repository
    from rigfem.context import Context
    from rigfem.sweep.run import SweepOptions

    table = run_sweep(p, Context(cache, OBSERVER, workers=args.workers),
                      SweepOptions(args.chunk_size, args.scheduler, configs=tuple(configs)))
    OBSERVER.stage("report")
    files = write_report(table, p, out, table.attrs.get("compute_seconds"))
    ok = table[table["status"] == "ok"]
    print(f"{p.linkage_type}: {len(table)} configurations, {len(ok)} computed, "
          f"{int((ok['verdict'] == 'fail').sum())} fail; wrote {', '.join(str(out / f) for f in files)}",
          file=sys.stdout)
    wrote(out)
    return 0
