"""What every real-time blur mode shares: the blur-length limit and the velocity convention.

The G-buffer holds the full displacement D over the exposure (world/conventions.py); the
filters blur symmetrically from -D/2 to +D/2, so their "half vector" is v = D/2, and a
method that clamps the blur length clamps |v| to `max_radius_px`.
"""
from __future__ import annotations

import math

from viewer.render.graph.params import group, param


@group("blur")
class BlurParams:
    max_radius: float = param(0.08, unit="fraction of the image width", lo=0.002, hi=0.25, effect="realloc",
                              help="largest blur per side, as a fraction of the image width "
                                   "(McGuire's tile size k, UE4's maximum); shared by all modes")


def max_radius_px(frame) -> int:
    """The blur limit in whole pixels (at least 1) for this frame's width."""
    return max(1, int(math.ceil(frame.params["blur"].max_radius * frame.size[0])))
