"""``rigfem compare A B``: two designs side by side, per part and mode; exit 1 when a verdict got worse.

A and B are result folders (written by ``rigfem check``) or scenes (a file or a built-in name),
which are checked first (no pictures, nothing kept but the comparison).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from rigfem.cli.exitcodes import FAIL, PASS
from rigfem.cli.outputs import mark_folder, new_folder, write_text, wrote
from rigfem.cli.progress import OBSERVER
from rigfem.errors import InputError, plain

HELP = "compare two result folders or scenes part by part: peaks, utilisation, bands and verdicts"
#: exit code 0 and 1 of this command (it has no verdict of its own, but says whether one got worse)
SUCCESS = f"no verdict got worse, {FAIL} a verdict got worse (a part case's or the overall)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("a", metavar="A", help="the reference: a result folder (with report.json) or a scene")
    p.add_argument("b", metavar="B", help="the design compared with it: a result folder or a scene")
    p.add_argument("--out", metavar="DIR", help="also write compare.md, compare.html and compare.json here")
    p.add_argument("--force", action="store_true", help="write into an existing --out folder rigfem wrote")
    p.add_argument("--fidelity", help="draft | standard | fine, for a scene that is checked (default: the scene's)")
    p.add_argument("--json", action="store_true", help="print the comparison as JSON instead of the table")


def _report(what: str, fidelity: str | None) -> tuple[str, dict]:
    """The report of ``what``: a result folder's report.json, or a scene checked now."""
    p = Path(what)
    if p.is_dir():
        f = p / "report.json"
        if not f.is_file():
            raise InputError(f"{plain(what, 120)!r} is a folder without report.json: give a folder written by "
                             f"`rigfem check`, or a scene")
        try:
            report = json.loads(f.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise InputError(f"{plain(str(f), 120)}: not a readable report ({plain(exc, 120)})") from None
        if not isinstance(report, dict) or not isinstance(report.get("parts"), list) or "verdict" not in report:
            raise InputError(f"{plain(str(f), 120)}: not a rigfem check report (no parts or verdict)")
        return p.name or str(p), report
    from rigfem.cache import from_environment
    from rigfem.context import Context
    from rigfem.pipeline import Output, Request, run_check

    overrides = {"frames": 0, **({"fidelity": fidelity} if fidelity else {})}
    with tempfile.TemporaryDirectory(prefix="rigfem-compare-") as tmp:
        OBSERVER.stage(f"checking {plain(what, 60)}")
        report = run_check(Request(what, overrides), Output(Path(tmp) / "check", pictures=False),
                           Context(from_environment(), OBSERVER))
    return report["scene"], report


def run(args: argparse.Namespace) -> int:
    from rigfem.report.compare import compare, render_compare_html, render_compare_markdown

    out = new_folder("--out", args.out, args.force) if args.out is not None else None
    (na, a), (nb, b) = _report(args.a, args.fidelity), _report(args.b, args.fidelity)
    if na == nb:
        na, nb = f"A ({na})", f"B ({nb})"
    c = compare(a, b, (na, nb))
    md = render_compare_markdown(c)
    print(json.dumps(c, indent=2) if args.json else md)
    if out is not None:
        mark_folder(out)
        write_text(out / "compare.md", md)
        write_text(out / "compare.html", render_compare_html(c))
        write_text(out / "compare.json", json.dumps(c, indent=2, allow_nan=False) + "\n")
        wrote(f"{out} (compare.md, compare.html, compare.json)")
    return FAIL if c["worse"] else PASS
