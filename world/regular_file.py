"""Reading a file that a user or a scene names: through a descriptor opened without
blocking and checked before any read (a FIFO never blocks, /dev/zero is never read, a
file swapped after a path check is caught by its descriptor), its size bounded first.
Callers turn the exceptions into their own one-line errors."""
from __future__ import annotations

import os
import stat


class NotRegular(OSError):
    """A folder, device, FIFO or socket."""


class TooLarge(OSError):
    def __init__(self, size: int):
        super().__init__(f"{size} bytes")
        self.size = size


class Grew(OSError):
    """The file grew between its size check and the end of the read."""


def read_regular(path, cap: int, before_read=None) -> bytes:
    """The bytes of the regular file `path` of at most `cap` bytes. `before_read(size)` runs
    once the size is known and before the bytes are read (a budget to take them from).
    FileNotFoundError and other OSErrors of the open pass through."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise NotRegular("not a regular file")
        if st.st_size > cap:
            raise TooLarge(st.st_size)
        os.set_blocking(fd, True)
        if before_read is not None:
            before_read(st.st_size)
    except BaseException:
        os.close(fd)
        raise
    with os.fdopen(fd, "rb") as f:
        data = f.read(st.st_size + 1)         # (read(n) allocates n bytes first)
    if len(data) > st.st_size:
        raise Grew("grew while it was read")
    return data
