"""The ``rigfem`` command: one module per subcommand in this package.

Each subcommand module defines ``HELP`` (one line), ``add_arguments(parser)`` and
``run(args) -> int`` (the exit code); a command without a verdict also defines ``SUCCESS``,
the meaning of its exit code 0 (its ``--help`` then lists no verdict codes).  Bad input raises :class:`rigfem.errors.InputError`
(one line on stderr, exit 2); what rigfem could not compute raises
:class:`rigfem.errors.ComputeError` (exit 3).  Any other exception is an internal error: one
line and exit 3, the traceback only with ``--debug``.  Ctrl-C and SIGTERM end quietly.

The environment is never an internal error: an output encoding that cannot show σ or … (ASCII,
``PYTHONIOENCODING=ascii``) gets ASCII words (``sigma_u/2``); a closed stdout or stderr reads as
/dev/null (the result stands); a full disk or file-size limit is "could not write PATH: no space
left" (exit 3); a name the file system refuses as too long is bad input (exit 2); any other
operating-system error is one line, exit 3.
"""

from __future__ import annotations

import argparse
import codecs
import contextlib
import errno
import importlib
import os
import re
import signal
import sys
import traceback
import unicodedata

from rigfem.cli.exitcodes import BAD_INPUT, INTERRUPTED, NO_COMPUTE, PIPE_CLOSED, TABLE, TERMINATED, table
from rigfem.cli.progress import heartbeat
from rigfem.errors import ComputeError, InputError, NoSpaceError, plain
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


#: what a character an output encoding cannot show is written as (σu/2 -> sigma_u/2)
ASCII = {"σ": "sigma", "τ": "tau", "μ": "mu", "ω": "omega", "α": "alpha", "β": "beta", "γ": "gamma",
         "θ": "theta", "π": "pi", "Δ": "delta", "ε": "eps", "ν": "nu", "ρ": "rho", "…": "...", "–": "-", "—": "-",
         "−": "-", "×": "x", "·": "*", "≤": "<=", "≥": ">=", "≈": "~", "±": "+/-", "→": "->", "°": " deg",
         "²": "^2", "³": "^3", "√": "sqrt", "Ø": "dia ", "‰": " per mille", "’": "'", "‘": "'", "“": '"', "”": '"'}


def _ascii(exc: UnicodeError) -> tuple[str, int]:
    """Codec error handler: the characters ``exc`` could not encode as ASCII words (a Greek
    letter before a name part gets an underscore: σu -> sigma_u), else their unaccented letters,
    else '?' (a file name's undecodable bytes, kept as surrogates, become '?' too)."""
    if not isinstance(exc, UnicodeEncodeError):
        raise exc
    text, end = exc.object, exc.end
    out = []
    for i in range(exc.start, end):
        c = text[i]
        word = ASCII.get(c) or unicodedata.normalize("NFKD", c).encode("ascii", "ignore").decode() or "?"
        if word.isalpha() and len(word) > 1 and i + 1 < len(text) and text[i + 1].isalnum():
            word += "_"
        out.append(word)
    return "".join(out), end


codecs.register_error("rigfem-ascii", _ascii)


def _streams() -> None:
    """Standard streams a command can always write: a closed fd 0, 1 or 2 opened on /dev/null
    (so no file rigfem opens lands on it), a missing sys.stdout/stderr set to it, and every
    character the terminal's encoding lacks written in ASCII."""
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            os.open(os.devnull, os.O_RDWR)   # the lowest free fd: this one
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is None:
            setattr(sys, name, open(os.devnull, "w", encoding="utf-8"))
        elif hasattr(stream, "reconfigure"):
            with contextlib.suppress(ValueError, OSError):
                stream.reconfigure(errors="rigfem-ascii")


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so ``finally`` blocks clean up as for Ctrl-C."""


def _on_sigterm(signum, frame) -> None:
    raise _Terminated()


def main(argv: list[str] | None = None) -> int:
    _streams()
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
    except NoSpaceError as exc:
        print(f"rigfem: {exc}", file=sys.stderr)
        return NO_COMPUTE
    except ComputeError as exc:
        print(f"rigfem: could not compute: {exc}", file=sys.stderr)
        return NO_COMPUTE
    except OSError as exc:  # the environment (disk, names, permissions), not a bug of rigfem
        if args.debug:
            traceback.print_exc()
        return _os_error(exc, args)
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


def _os_error(exc: OSError, args: argparse.Namespace) -> int:
    """One line for an operating-system error no layer below turned into a message: a name too
    long is bad input (exit 2); a full disk and anything else could not be done (exit 3).  Without
    the file's name, the command's outputs are named."""
    flags = [f"--{k.replace('_', '-')} {getattr(args, k)}" for k in ("out", "csv", "plot", "animate", "scene_out")
             if getattr(args, k, None)]
    where = (plain(exc.filename, 160) if exc.filename is not None else
             f"the outputs of rigfem {_what(args)}" + (f" ({plain(', '.join(flags), 160)})" if flags else ""))
    if exc.errno == errno.ENAMETOOLONG:
        print(f"rigfem: error: {where}: the name is longer than the file system allows", file=sys.stderr)
        return BAD_INPUT
    if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
        print(f"rigfem: could not write {where}: no space left ({exc.strerror})", file=sys.stderr)
        return NO_COMPUTE
    print(f"rigfem: could not compute: {where}: {exc.strerror or exc}", file=sys.stderr)
    return NO_COMPUTE


def _what(args: argparse.Namespace) -> str:
    """The command (and task) a progress line names."""
    return " ".join(str(w) for w in (args.command, getattr(args, "task", None)) if w)


if __name__ == "__main__":
    sys.exit(main())
