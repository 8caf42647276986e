"""``rigfem verify --against calculix SCENE``: every part case of a check re-solved by CalculiX.

The critical load combination (crank angle) of each part case is exported with the same
mesh, supports and nodal loads, solved by ccx, and the peak von Mises and displacements
compared.  Exit 0 when every case agrees within the tolerances, 1 otherwise, 2 on bad input
or when ccx is not installed.
"""

from __future__ import annotations

import argparse
import json
import shutil
import time
from pathlib import Path

from rigfem.cli.linkage_args import add_rule_argument
from rigfem.cli.outputs import mark_folder, new_folder, write_text, wrote
from rigfem.cli.progress import OBSERVER
from rigfem.errors import InputError, check_range, check_whole, plain
from rigfem.settings import REFERENCE_SCENE

HELP = "independent verification: re-solve every part case of a scene in CalculiX and compare"
#: the meaning of exit codes 0 and 1
SUCCESS = "every case agrees within the tolerances, 1 a case does not"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", nargs="?", default=REFERENCE_SCENE,
                   help=f"scene file or built-in name (default {REFERENCE_SCENE}, the same as rigfem check's)")
    p.add_argument("--against", default="calculix", help="the other solver (calculix)")
    p.add_argument("--fidelity", default="draft", help="draft | standard | fine (default draft)")
    p.add_argument("--threads", default="1", help="ccx threads (default 1)")
    p.add_argument("--peak-tol", default="1.0", help="allowed peak von Mises difference, %% (default 1)")
    p.add_argument("--disp-tol", default="0.5", help="allowed displacement difference, %% (default 0.5)")
    p.add_argument("--out", metavar="DIR", help="also write calculix_verify_<scene>.md/.json into DIR (a new folder, "
                                                "or with --force one rigfem wrote)")
    p.add_argument("--force", action="store_true", help="write into an existing --out folder rigfem wrote")
    add_rule_argument(p)


def table(rows: list[dict], title: str, command: str, seconds: float) -> str:
    """Markdown table of verify rows."""
    lines = [f"# {title}", "", f"Command: `{command}` ({seconds:.0f} s)  ",
             "Each part case's critical load combination, same mesh/supports/loads, solved by ccx.", "",
             "| part | mode | DOF | peak σvm rigfem [MPa] | ccx [MPa] | Δ peak | max Δu / max u |",
             "|---|---|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['part']} | {r['mode']} | {r['dof']} | {r['peak_von_mises']:.3f} | "
              f"{r['peak_von_mises_ccx']:.3f} | {100 * r['peak_rel_diff']:+.4f} % | "
              f"{100 * r['displacement_rel_diff']:.4f} % |" for r in rows]
    if rows:
        worst = max(abs(r["peak_rel_diff"]) for r in rows)
        lines += ["", f"Largest peak difference {100 * worst:.4f} % (the .frd holds 5 significant digits)."]
    return "\n".join(lines) + "\n"


def run(args: argparse.Namespace) -> int:
    from rigfem.cache import from_environment
    from rigfem.context import Context
    from rigfem.job import Request, read_job
    from rigfem.verification.calculix import verify_job

    # every option and the scene are checked before ccx is looked for and before any computation
    if args.against != "calculix":
        raise InputError(f"--against = {args.against!r}: the only other solver is 'calculix'")
    threads = check_whole("--threads", args.threads, 1, 64)
    peak_tol = check_range("--peak-tol", args.peak_tol, 0.0, 100.0, "%")
    disp_tol = check_range("--disp-tol", args.disp_tol, 0.0, 100.0, "%")
    out = new_folder("--out", args.out, args.force) if args.out else None
    ctx = Context(from_environment(), OBSERVER)
    job = read_job(Request(args.scene, {"fidelity": args.fidelity, "frames": 0}, args.allow_rule_violations),
                   ctx.cache)
    if shutil.which("ccx") is None:
        raise InputError("--against calculix needs the ccx program (Debian: apt-get install calculix-ccx)")
    t0 = time.perf_counter()
    rows = verify_job(job, threads, ctx)
    name = Path(str(args.scene)).stem
    command = f"rigfem verify --against calculix {args.scene} --fidelity {args.fidelity} --threads {threads}"
    text = table(rows, f"rigfem vs CalculiX 2.20: scene {name} ({args.fidelity})", command,
                 time.perf_counter() - t0)
    text = "".join(f"WARNING: breaks rig rule {plain(v)} (--allow-rule-violations)\n" for v in job.rule_violations) + text
    print(text, end="")
    if out is not None:
        OBSERVER.stage("report")
        mark_folder(out)
        write_text(out / f"calculix_verify_{name}.md", text)
        write_text(out / f"calculix_verify_{name}.json", json.dumps(
            {"scene": name, "fidelity": args.fidelity, "ccx_threads": threads, "command": command,
             "rule_violations": list(job.rule_violations),
             "cases": rows}, indent=2) + "\n")
        wrote(out / f"calculix_verify_{name}.md", out / f"calculix_verify_{name}.json")
    ok = all(abs(r["peak_rel_diff"]) * 100 <= peak_tol and r["displacement_rel_diff"] * 100 <= disp_tol
             for r in rows)
    return 0 if ok else 1
