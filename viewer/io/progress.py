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


class Progress:
    def __init__(self, label: str, stream=None):
        self.label, self.stream = label, stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.t0 = time.perf_counter()
        self._last = -1

    def __call__(self, k: int, n: int):
        done = k + 1
        global _open_line
        if self.tty:
            bar = "#" * (20 * done // n)
            self.stream.write(f"\r{self.label} [{bar:<20}] {done}/{n}")
            _open_line = self.stream
            if done == n:
                self.stream.write(f"  {time.perf_counter() - self.t0:.1f} s\n")
                _open_line = None
            self.stream.flush()
        else:
            quarter = 4 * done // n
            if quarter != self._last and (quarter > 0 or done == 1):
                self._last = quarter
                self.stream.write(f"{self.label}: {done}/{n}\n")
                self.stream.flush()
