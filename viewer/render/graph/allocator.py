"""Keep freed host memory in the process for the next frame (glibc's malloc).

A frame allocates numpy arrays of tens to hundreds of kilobytes (ray batches, hit
records, tile maps). glibc serves each one of 128 kB and more from a fresh mmap and
unmaps it when freed, and trims the heap's top when free space there passes 128 kB: each
frame then pays a page fault per 4 kB page it touches again (docs/architecture.md, "Fresh
memory faults per page"). A real-time loop reuses the same
sizes frame after frame, so the renderer asks malloc to serve blocks up to 32 MB from
the heap and to keep up to 256 MB free there: the process holds on to its peak heap.
"""
from __future__ import annotations

import ctypes
import ctypes.util

# mallopt parameters (glibc's malloc.h).
M_TRIM_THRESHOLD, M_TOP_PAD, M_MMAP_THRESHOLD = -1, -2, -3
SETTINGS = ((M_MMAP_THRESHOLD, 32 << 20), (M_TRIM_THRESHOLD, 256 << 20), (M_TOP_PAD, 16 << 20))

_done = False


def keep_freed_memory() -> bool:
    """Apply SETTINGS once per process; False where there is no glibc mallopt (other C
    libraries keep their own policy: nothing else depends on this)."""
    global _done
    if _done:
        return True
    try:
        mallopt = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    _done = all(mallopt(param, value) == 1 for param, value in SETTINGS)
    return _done
