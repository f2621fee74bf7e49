"""viewer/render/graph/allocator.py: with its settings, a frame's host arrays reuse memory the
process already touched instead of faulting fresh pages in every time."""
from __future__ import annotations

import subprocess
import sys

import pytest

from viewer.render.graph import allocator

PROBE = """
import resource, sys
import numpy as np
from viewer.render.graph.allocator import keep_freed_memory
if sys.argv[1] == "1":
    assert keep_freed_memory()
def frame():
    # A frame's temporaries: several arrays of ~half a megabyte alive together, then freed.
    arrays = [np.ones(1 << 16) for _ in range(12)]
    return sum(a.sum() for a in arrays)
frame()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    frame()
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def page_faults(keep: bool) -> int:
    out = subprocess.run([sys.executable, "-c", PROBE, "1" if keep else "0"], check=True,
                         capture_output=True, text=True)
    return int(out.stdout.split()[-1])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_freed_arrays_are_reused_without_page_faults():
    # 20 frames of 12 arrays of 128 pages: glibc's defaults give the memory back after
    # each frame and fault it in again in the next.
    assert page_faults(keep=False) > 20 * 12 * 128 // 2
    assert page_faults(keep=True) < 12 * 128
    assert allocator.keep_freed_memory()
