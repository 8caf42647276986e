"""The ``rigfem`` command: one module per subcommand in this package.

Each subcommand module defines ``HELP`` (one line), ``add_arguments(parser)`` and
``run(args) -> int`` (the exit code); a command without a verdict also defines ``SUCCESS``,
the meaning of its exit code 0 (its ``--help`` then lists no verdict codes).  Bad input raises :class:`rigfem.errors.InputError`
(one line on stderr, exit 2); what rigfem could not compute raises
:class:`rigfem.errors.ComputeError` (exit 3).  Any other exception is an internal error: one
line and exit 3, the traceback only with ``--debug``.  Ctrl-C and SIGTERM end quietly.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import re
import signal
import sys
import traceback

from rigfem.cli.exitcodes import BAD_INPUT, INTERRUPTED, NO_COMPUTE, PIPE_CLOSED, TABLE, TERMINATED, table
from rigfem.cli.progress import heartbeat
from rigfem.errors import ComputeError, InputError
from rigfem.settings import ALLOW_LARGE_ENV

#: subcommand name -> module under rigfem.cli (added as the capabilities land)
COMMANDS: dict[str, str] = {
    "check": "check",
    "kinematics": "kinematics",
    "convergence": "convergence",
    "mesh": "mesh",
    "parts": "parts",
    "reactions": "reactions",
    "verify": "verify",
    "sweep": "sweep",
    "show": "show",
    "compare": "compare",
    "synthesize": "synthesize",
    "cache": "cache",
}


def _available(only: str | None = None) -> dict[str, object]:
    """Every subcommand module, for the command list: each is light at import (its heavy imports
    are inside ``run``), so ``rigfem --help`` loads no FE, mesh or plotting code.  With ``only``
    (the command given) just that one: the others' help is never printed then."""
    names = [only] if only in COMMANDS else COMMANDS
    return {name: importlib.import_module(f"rigfem.cli.{COMMANDS[name]}") for name in names}


class _Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """Every default shown: argparse's ``(default: X)`` unless the help already names it."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if ("default" in text or action.default in (None, False, "", [], argparse.SUPPRESS)
                or not action.option_strings):
            return text
        return super()._get_help_string(action)


#: what a negative number looks like on the command line (argparse's own misses -1e-05 and -inf)
_NEGATIVE = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    """argparse with exit code 2, a one-line message and every default in ``--help``."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE  # -1e-05, -inf: values, not options

    def error(self, message: str) -> None:  # noqa: D401 - argparse API
        self.exit(2, f"rigfem: error: {message}\n")


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("rigfem")
    except PackageNotFoundError:
        return "unknown (not installed)"


class _Version(argparse.Action):
    """``--version``: the installed version, read (importlib.metadata, ~0.1 s) only when asked."""

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        print(f"rigfem {_version()}")
        parser.exit()


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    parser = _Parser(prog="rigfem", description="Stress checker for the configurable-bar linkage rig.",
                     epilog=TABLE)
    parser.add_argument("--debug", action="store_true", help="show the traceback of an internal error")
    parser.add_argument("--allow-large", action="store_true",
                        help="run jobs whose cost estimate exceeds the machine's memory or a documented limit")
    parser.add_argument("--version", action=_Version, nargs=0, help="show program's version number and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    words = [a for a in (sys.argv[1:] if argv is None else argv) if not a.startswith("-")]
    chosen = _available(words[0] if words else None)
    for name in (n for n in COMMANDS if n not in chosen):  # a name only: its module is not imported
        sub.add_parser(name)
    for name, mod in chosen.items():
        p = sub.add_parser(name, help=mod.HELP, description=mod.HELP, epilog=table(getattr(mod, "SUCCESS", None)))
        if words and words[0] == name:  # only the chosen command's options (they may load its defaults)
            mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so ``finally`` blocks clean up as for Ctrl-C."""


def _on_sigterm(signum, frame) -> None:
    raise _Terminated()


def main(argv: list[str] | None = None) -> int:
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return BAD_INPUT
    if args.allow_large:  # read below the CLI (rigfem.settings.allow_large), also by child processes
        os.environ[ALLOW_LARGE_ENV] = "1"
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        from rigfem.cache import from_environment

        from_environment()  # the cache's folder and limit: one rule, checked before any command runs
        with (contextlib.nullcontext() if getattr(args, "quiet", False) else
              heartbeat(_what(args))):   # --quiet: no progress of any kind
            code = int(args._run(args) or 0)
        sys.stdout.flush()
        return code
    except BrokenPipeError:  # `rigfem ... | head`: the reader left; end quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return PIPE_CLOSED
    except InputError as exc:
        print(f"rigfem: error: {exc}", file=sys.stderr)
        return BAD_INPUT
    except ComputeError as exc:
        print(f"rigfem: could not compute: {exc}", file=sys.stderr)
        return NO_COMPUTE
    except KeyboardInterrupt:
        print("rigfem: interrupted", file=sys.stderr)
        return INTERRUPTED
    except _Terminated:
        print("rigfem: terminated", file=sys.stderr)
        return TERMINATED
    except Exception as exc:  # an internal error: one line unless the user asks for the traceback
        if args.debug:
            traceback.print_exc()
        print(f"rigfem: internal error: {type(exc).__name__}: {exc} (rerun with --debug for the "
              f"traceback)", file=sys.stderr)
        return NO_COMPUTE
    finally:
        signal.signal(signal.SIGTERM, previous)


def _what(args: argparse.Namespace) -> str:
    """The command (and task) a progress line names."""
    return " ".join(str(w) for w in (args.command, getattr(args, "task", None)) if w)


if __name__ == "__main__":
    sys.exit(main())
