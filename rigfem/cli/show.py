"""``rigfem show``: open a result folder's HTML report in the browser (or print where it is), or
print it to PDF through headless Chromium (the report's print stylesheet: A4, a page per part)."""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import tempfile
import webbrowser
from pathlib import Path

from rigfem.errors import ComputeError, InputError

HELP = "open a result folder's report.html in the browser (or print its path, or print it to PDF)"
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = "report opened, its path printed or its PDF written"
#: the browsers that can print a page to PDF headless, in the order they are tried
CHROMIUM = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
#: longest a PDF may take to print, s
PDF_TIMEOUT_S = 300


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("folder", metavar="RESULT_FOLDER", help="a folder written by rigfem check")
    p.add_argument("--print", dest="print_only", action="store_true", help="only print the report's path")
    p.add_argument("--pdf", nargs="?", const="", metavar="PATH",
                   help="print the report to PDF through headless Chromium (default PATH: report.pdf in the folder)")


def chromium() -> str:
    """The headless browser that prints the PDF; ComputeError (exit 3) naming the package when none is installed."""
    found = next((p for p in map(shutil.which, CHROMIUM) if p), None)
    if found is None:
        raise ComputeError("rigfem show --pdf prints through headless Chromium, and none is installed "
                           "(Debian/Ubuntu: apt-get install chromium)")
    return found


def write_pdf(html: Path, pdf: Path) -> Path:
    """Print ``html`` to ``pdf`` with headless Chromium (A4, the page's print stylesheet, no header or footer)."""
    with tempfile.TemporaryDirectory(prefix="rigfem-pdf-") as profile:
        part = pdf.with_name(f".{pdf.name}.{os.getpid()}.part")
        cmd = [chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--no-pdf-header-footer",
               f"--user-data-dir={profile}", f"--print-to-pdf={part}", html.resolve().as_uri()]
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=PDF_TIMEOUT_S,
                                  stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            part.unlink(missing_ok=True)
            raise ComputeError(f"Chromium did not print {html} within {PDF_TIMEOUT_S} s") from None
        if done.returncode != 0 or not part.is_file() or not part.read_bytes().startswith(b"%PDF-"):
            part.unlink(missing_ok=True)
            last = (done.stderr.strip().splitlines() or ["no message"])[-1][:200]
            raise ComputeError(f"Chromium could not print {html} to PDF (exit {done.returncode}: {last})")
        part.replace(pdf)
    return pdf


def run(args: argparse.Namespace) -> int:
    report = Path(args.folder) / "report.html"
    if not report.is_file():
        raise InputError(f"RESULT_FOLDER = {str(args.folder)!r} has no report.html: give a folder written "
                         f"by `rigfem check` (run the check again to write its HTML report)")
    if args.pdf is not None:
        pdf = Path(args.pdf) if args.pdf else report.with_suffix(".pdf")
        if pdf.is_dir() or not pdf.parent.is_dir():
            raise InputError(f"--pdf {str(args.pdf)!r}: give a file in an existing folder")
        print(write_pdf(report, pdf))
        return 0
    uri = report.resolve().as_uri()
    if args.print_only or not webbrowser.open(uri):
        print(report.resolve())
    return 0
