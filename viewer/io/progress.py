"""A one-line progress bar on stderr (redrawn in place on a terminal, sparse otherwise)."""
from __future__ import annotations

import sys
import time


# The stream whose last line a progress bar left open (no newline yet), if any.
_open_line = None


def end_line():
    """End a progress bar's open line, so that an error printed next starts its own."""
    global _open_line
    if _open_line is not None:
        _open_line.write("\n")
        _open_line.flush()
        _open_line = None


def is_terminal(stream) -> bool:
    return hasattr(stream, "isatty") and stream.isatty()


def redraw(stream, text: str, last: bool):
    """`text` over a terminal's current line; `last`: the line ends (else it stays open
    until the next redraw, or end_line)."""
    global _open_line
    stream.write("\r" + text + ("\n" if last else ""))
    _open_line = None if last else stream
    stream.flush()


class Progress:
    def __init__(self, label: str, stream=None):
        self.label, self.stream = label, stream or sys.stderr
        self.tty = is_terminal(self.stream)
        self.t0 = time.perf_counter()
        self._last = -1

    def __call__(self, k: int, n: int):
        done = k + 1
        if self.tty:
            bar = "#" * (20 * done // n)
            text = f"{self.label} [{bar:<20}] {done}/{n}"
            if done == n:
                text += f"  {time.perf_counter() - self.t0:.1f} s"
            redraw(self.stream, text, done == n)
        else:
            quarter = 4 * done // n
            if quarter != self._last and (quarter > 0 or done == 1):
                self._last = quarter
                self.stream.write(f"{self.label}: {done}/{n}\n")
                self.stream.flush()
