"""The ``rigfem`` command: one module per subcommand in this package.

Each subcommand module defines ``HELP`` (one line), ``add_arguments(parser)`` and
``run(args) -> int`` (the exit code).  Bad input raises :class:`rigfem.errors.InputError`,
printed here as one line on stderr with exit code 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from rigfem.errors import InputError

#: subcommand name -> module under rigfem.cli (added as the capabilities land)
COMMANDS: dict[str, str] = {
    "check": "check",
    "convergence": "convergence",
    "mesh": "mesh",
    "parts": "parts",
    "reactions": "reactions",
    "verify": "verify",
    "sweep": "sweep",
}


def _available() -> dict[str, object]:
    mods = {}
    for name, module in COMMANDS.items():
        mods[name] = importlib.import_module(f"rigfem.cli.{module}")
    return mods


class _Parser(argparse.ArgumentParser):
    """argparse with exit code 2 and a one-line message (argparse's own default is 2 too)."""

    def error(self, message: str) -> None:  # noqa: D401 - argparse API
        self.exit(2, f"rigfem: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="rigfem", description="Stress checker for the configurable-bar linkage rig.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, mod in _available().items():
        p = sub.add_parser(name, help=mod.HELP, description=mod.HELP)
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 2
    try:
        return int(args._run(args) or 0)
    except InputError as exc:
        print(f"rigfem: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
