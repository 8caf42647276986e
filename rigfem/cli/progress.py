"""Progress of a long command: after :data:`AFTER_S` seconds without a result, a line on stderr
every :data:`EVERY_S` seconds — redrawn in place on a terminal, plain log lines (command,
stage and elapsed time) otherwise, so CI logs and files show that the run is alive."""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Iterator

__all__ = ["AFTER_S", "EVERY_S", "heartbeat"]

AFTER_S, EVERY_S = 2.0, 10.0
_SPIN = "|/-\\"


@contextlib.contextmanager
def heartbeat(what: str, stream=None, after_s: float = AFTER_S, every_s: float = EVERY_S,
              terminal: bool | None = None, on_terminal: bool = True) -> Iterator[None]:
    """Report ``what`` (the command and its stage) with the elapsed time while the block runs;
    ``on_terminal`` False: nothing on a terminal (the command draws its own bar there)."""
    stream = stream or sys.stderr
    try:
        tty = stream.isatty() if terminal is None else terminal
    except (AttributeError, ValueError):
        tty = False
    if tty and not on_terminal:
        yield
        return
    stop = threading.Event()
    t0 = time.monotonic()
    drew = []

    def beat() -> None:
        if stop.wait(after_s):
            return
        while not stop.is_set():
            line = f"rigfem {what}: running, {time.monotonic() - t0:.0f} s elapsed"
            try:
                stream.write(f"\r{line} {_SPIN[len(drew) % 4]}" if tty else line + "\n")
                stream.flush()
            except (OSError, ValueError):
                return
            drew.append(1)
            if stop.wait(1.0 if tty else every_s):
                return

    thread = threading.Thread(target=beat, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        if drew and tty:
            with contextlib.suppress(OSError, ValueError):
                stream.write("\r\x1b[K")
                stream.flush()
