"""A virtual X display for window tests.

`Xvfb -displayfd` picks a free display number itself and writes it to a pipe once the
server accepts connections, so there is no guessing of numbers and no race with a server
that is still starting. Locally, a machine without Xvfb skips the window tests with a
reason; under CI (CI=true) it is a failure.
"""
from __future__ import annotations

import os
import select
import shutil
import subprocess
import tempfile
import time

import pytest

START_TIMEOUT_S = 20.0
SCREEN = "1920x1080x24"
# Would send GLX or PyOpenGL away from the X server's own (Mesa) libraries.
SCRUB = ("__GLX_VENDOR_LIBRARY_NAME", "PYOPENGL_PLATFORM", "WAYLAND_DISPLAY")


def require_xvfb() -> str:
    path = shutil.which("Xvfb")
    if path is None:
        reason = "Xvfb not installed (apt-get install xvfb): window tests need a virtual display"
        if os.environ.get("CI"):
            pytest.fail(reason)
        pytest.skip(reason)
    return path


def _read_line(fd: int, timeout: float) -> str:
    """Read up to a newline. Xvfb writes the number and the newline separately, and closing
    the pipe between the two kills it (it cannot write the newline)."""
    deadline = time.monotonic() + timeout
    data = b""
    while not data.endswith(b"\n"):
        left = deadline - time.monotonic()
        ready, _, _ = select.select([fd], [], [], max(left, 0.0))
        if not ready:
            break
        chunk = os.read(fd, 64)
        if not chunk:
            break
        data += chunk
    return data.decode(errors="replace").strip()


class Xvfb:
    def __init__(self, screen: str = SCREEN):
        self.screen = screen
        self.proc: subprocess.Popen | None = None
        self.display: str | None = None
        self.log = None

    def start(self) -> "Xvfb":
        exe = require_xvfb()
        read_fd, write_fd = os.pipe()
        try:
            # The server's chatter (keymap warnings on every connection) goes to a file: an
            # unread pipe would fill up and stall the server.
            self.log = tempfile.TemporaryFile()
            self.proc = subprocess.Popen(
                [exe, "-displayfd", str(write_fd), "-screen", "0", self.screen,
                 "-nolisten", "tcp", "-noreset"],
                pass_fds=(write_fd,), stdout=subprocess.DEVNULL, stderr=self.log)
            os.close(write_fd)
            write_fd = -1
            number = _read_line(read_fd, START_TIMEOUT_S)
        finally:
            os.close(read_fd)
            if write_fd >= 0:
                os.close(write_fd)
        if not number.isdigit():
            err = self.stop() or "no display number reported"
            raise RuntimeError(f"Xvfb did not start: {err}")
        self.display = f":{number}"
        return self

    def env(self, base: dict | None = None) -> dict:
        """An environment for a subprocess that draws on this display."""
        env = dict(os.environ if base is None else base)
        for key in SCRUB:
            env.pop(key, None)
        env["DISPLAY"] = self.display
        return env

    def stop(self) -> str:
        """Stop the server; returns what it wrote to stderr (for error messages)."""
        if self.proc is None:
            return ""
        proc, self.proc = self.proc, None
        if proc.poll() is None:
            proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        self.log.seek(0)
        err = self.log.read()[-2000:]
        self.log.close()
        return err.decode(errors="replace").strip()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()
