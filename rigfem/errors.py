"""The two kinds of failure: bad input (the user can fix it) and could-not-compute (rigfem could not).

Bad input is an InputError where input is parsed (a value out of its range), or an
InfeasibleError from inside (valid values that ask for what cannot be built or run).

The CLI maps them to exit codes 2 and 3; nothing below the CLI knows about exit codes.
"""

import os
import re

_CONTROL = re.compile(r"\x1b\[[0-?]*[ -/]*[@-~]|\x1b\][^\x07\x1b]*(\x07|\x1b\\)?|[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def plain(text: object, limit: int = 200) -> str:
    r"""``text`` on one line without ANSI escapes or control characters, at most ``limit``
    characters: user text (file names, descriptions, keys) safe for a terminal or an error line.

    >>> plain("\x1b[31mred\x1b[0m\nline")
    'red line'
    """
    s = _CONTROL.sub("", str(text).replace("\r\n", " ").replace("\n", " ").replace("\t", " "))
    return s if len(s) <= limit else s[: limit - 1] + "…"


class InputError(ValueError):
    """Bad user input: the message names the field, the value and the allowed range."""


class InfeasibleError(InputError):
    """Well-formed input that asks for what cannot be built or run, known only once rigfem works on
    it: no four-bar on the rig's rails, a joint off a rail's holes, a peak inside a toggle range, a
    mesh too coarse for its part, a job past this machine.  The user changes the input (an
    InputError: exit 2); the layers inside raise it, while a plain InputError (a value out of its
    range) is raised only where input is parsed."""


class ClosureError(InfeasibleError):
    """A linkage's lengths cannot close its loop (at all, or at the crank angles asked): the message
    names the lengths and the angles where it closes (:mod:`rigfem.linkage` raises it)."""


class ComputeError(RuntimeError):
    """Valid input that rigfem could not compute (mesher, solver, external program)."""


class NoSpaceError(ComputeError, OSError):
    """A file could not be written: its disk, quota or the file-size limit is full (the message
    names the file and its folder).  Also an OSError, so code that goes on without a cache entry
    it could not write still does."""


def check_range(name: str, value: float, lo: float | None = None, hi: float | None = None,
                unit: str = "", lo_open: bool = False) -> float:
    """Return ``value`` as float if finite and inside [lo, hi]; raise InputError naming ``name``."""
    if isinstance(value, bool):
        raise InputError(f"{name} must be a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    u = f" {unit}" if unit else ""
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    bracket = "(" if lo_open else "["
    if (v != v or v in (float("inf"), float("-inf"))
            or (lo is not None and (v < lo or (lo_open and v == lo)))
            or (hi is not None and v > hi)):
        raise InputError(f"{name} = {value!r}{u} is outside the allowed range {bracket}{lo_s}, {hi_s}]{u}")
    return v


def check_whole(name: str, value: object, lo: int, hi: int) -> int:
    """``value`` as an int if it is a whole number inside [lo, hi]; InputError naming ``name``
    (1.5 threads is refused, not read as 1)."""
    v = check_range(name, value, lo, hi)
    if v != int(v):
        raise InputError(f"{name} = {value!r} must be a whole number in [{lo}, {hi}]")
    return int(v)


_BOMS = ((b"\xef\xbb\xbf", "utf-8"), (b"\xff\xfe", "utf-16-le"), (b"\xfe\xff", "utf-16-be"))


def decode_text(blob: bytes, what: str) -> str:
    """Text of a file as other programs write it: UTF-8 with or without BOM (Excel CSV), UTF-16
    with BOM or without (Windows tools), CRLF or CR line ends (read as LF); InputError naming
    ``what`` for real binary (NUL bytes) or text in another encoding."""
    enc, body = "utf-8", blob
    for bom, name in _BOMS:
        if blob.startswith(bom):
            enc, body = name, blob[len(bom):]
            break
    else:
        if len(blob) >= 4 and blob[1::2].count(0) > 0.9 * (len(blob) // 2) and blob[0::2].count(0) == 0:
            enc = "utf-16-le"
        elif len(blob) >= 4 and blob[0::2].count(0) > 0.9 * (len(blob) // 2) and blob[1::2].count(0) == 0:
            enc = "utf-16-be"
    try:
        text = body.decode(enc)
    except UnicodeDecodeError as exc:
        if b"\x00" in blob:
            raise InputError(f"{what} is a binary file, not text") from None
        raise InputError(f"{what} is not UTF-8 or UTF-16 text (byte {exc.start}); save it as UTF-8") from None
    if "\x00" in text:
        raise InputError(f"{what} is a binary file, not text")
    return text.replace("\r\n", "\n").replace("\r", "\n")


def read_at_most(path: "os.PathLike | str", limit: int, what: str, kind: str) -> bytes:
    """The bytes of the file ``path`` if it holds at most ``limit``; InputError naming ``what`` if
    it cannot be read or is larger (its size is checked before anything is read: a 4 GB file is
    refused, not loaded; what grows while read is cut at ``limit`` + 1 bytes and refused)."""
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            blob = fh.read(limit + 1) if size <= limit else b""
    except OSError as exc:
        raise InputError(f"{what} cannot be read: {plain(exc.strerror or exc, 80)}") from None
    if size > limit or len(blob) > limit:
        raise InputError(f"{what} is {max(size, len(blob))} bytes; {kind} is at most {limit} bytes")
    return blob
