"""Progress of a long command, by stage: after :data:`AFTER_S` seconds a line on stderr naming
the command, its stage and the elapsed time — redrawn in place on a terminal; plain log lines
otherwise (CI logs, files): one when each stage begins and one every :data:`EVERY_S` seconds,
``rigfem <command>: <stage> · <done>/<total> <unit> … <elapsed> s``.  Library code never prints: it
reports to the :class:`rigfem.observer.Observer` of its context, and the CLI's is :data:`OBSERVER`,
which shows the same on a terminal as in a log."""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Iterator

from rigfem.observer import Observer

__all__ = ["AFTER_S", "EVERY_S", "heartbeat", "stage", "OBSERVER"]

AFTER_S, EVERY_S = 2.0, 10.0
_SPIN = "|/-\\"
_LIVE: list[_Beat] = []   # the running command's reporter (main installs one per command)


class _Beat:
    """What one command reports: its name, current stage, start time and where lines go."""

    def __init__(self, what: str, stream, tty: bool) -> None:
        self.what, self.stream, self.tty = what, stream, tty
        self.stage, self.t0, self.lines, self.count = "running", time.monotonic(), 0, ""
        self.lock = threading.Lock()

    def line(self) -> None:
        """Write the current line (the caller decides when)."""
        text = f"rigfem {self.what}: {self.stage}{self.count} … {time.monotonic() - self.t0:.0f} s"
        with self.lock, contextlib.suppress(OSError, ValueError):
            self.stream.write(f"\r\x1b[K{text} {_SPIN[self.lines % 4]}" if self.tty else text + "\n")
            self.stream.flush()
            self.lines += 1


def stage(name: str) -> None:
    """The running command entered stage ``name`` (e.g. 'meshing part crank'); a plain line at
    once once the command has run :data:`AFTER_S` seconds (quick commands stay quiet)."""
    if not _LIVE:
        return
    beat = _LIVE[-1]
    beat.stage, beat.count = name, ""
    if not beat.tty and beat.lines:
        beat.line()


def step(done: int, total: int, what: str) -> None:
    """The running command finished ``done`` of ``total`` counted steps (shown beside the stage)."""
    if _LIVE:
        _LIVE[-1].count = f" · {done}/{total} done"


class _Progress(Observer):
    """The command line's observer: stages and counts on the progress line."""

    def stage(self, text: str) -> None:
        stage(text)

    def step(self, done: int, total: int, what: str) -> None:
        step(done, total, what)


#: the observer every command hands its library calls
OBSERVER = _Progress()


@contextlib.contextmanager
def heartbeat(what: str, stream=None, after_s: float | None = None, every_s: float | None = None,
              terminal: bool | None = None) -> Iterator[None]:
    """Report ``what`` (the command) with its stage and the elapsed time while the block runs
    (first after ``after_s``, default :data:`AFTER_S`, then every ``every_s``, default :data:`EVERY_S`)."""
    after_s = AFTER_S if after_s is None else after_s
    every_s = EVERY_S if every_s is None else every_s
    stream = stream or sys.stderr
    try:
        tty = stream.isatty() if terminal is None else terminal
    except (AttributeError, ValueError):
        tty = False
    beat = _Beat(what, stream, tty)
    stop = threading.Event()

    def run() -> None:
        if stop.wait(after_s):
            return
        while not stop.is_set():
            beat.line()
            if stop.wait(1.0 if tty else every_s):
                return

    thread = threading.Thread(target=run, daemon=True)
    _LIVE.append(beat)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        _LIVE.remove(beat)
        if beat.lines and tty:
            with contextlib.suppress(OSError, ValueError):
                stream.write("\r\x1b[K")
                stream.flush()
