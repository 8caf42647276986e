"""``rigfem show``: open a result folder's HTML report in the browser (or print where it is)."""

from __future__ import annotations

import argparse
import webbrowser
from pathlib import Path

from rigfem.errors import InputError

HELP = "open a result folder's report.html in the browser (or print its path)"
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = "report opened or its path printed"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("folder", metavar="RESULT_FOLDER", help="a folder written by rigfem check")
    p.add_argument("--print", dest="print_only", action="store_true", help="only print the report's path")


def run(args: argparse.Namespace) -> int:
    report = Path(args.folder) / "report.html"
    if not report.is_file():
        raise InputError(f"RESULT_FOLDER = {str(args.folder)!r} has no report.html: give a folder written "
                         f"by `rigfem check` (run the check again to write its HTML report)")
    uri = report.resolve().as_uri()
    if args.print_only or not webbrowser.open(uri):
        print(report.resolve())
    return 0
