"""A one-line progress bar on stderr (redrawn in place on a terminal, sparse otherwise)."""
from __future__ import annotations

import sys
import time


class Progress:
    def __init__(self, label: str, stream=None):
        self.label, self.stream = label, stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.t0 = time.perf_counter()
        self._last = -1

    def __call__(self, k: int, n: int):
        done = k + 1
        if self.tty:
            bar = "#" * (20 * done // n)
            self.stream.write(f"\r{self.label} [{bar:<20}] {done}/{n}")
            if done == n:
                self.stream.write(f"  {time.perf_counter() - self.t0:.1f} s\n")
            self.stream.flush()
        else:
            quarter = 4 * done // n
            if quarter != self._last and (quarter > 0 or done == 1):
                self._last = quarter
                self.stream.write(f"{self.label}: {done}/{n}\n")
                self.stream.flush()
