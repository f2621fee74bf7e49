"""Parameters of how every real-time mode samples the motion over the exposure, one
`@group("motion")` read by the renderer around any pipeline (viewer/render/steps.py)."""
from __future__ import annotations

from ..params import group, param

MAX_STEPS = 256


@group("motion")
class MotionParams:
    steps: int = param(1, lo=1, hi=MAX_STEPS,
                       help="sub-exposure steps: the frame as this many sub-frames at the "
                            "centres of equal parts of the exposure, each blurred by the "
                            "mode over its part, averaged in linear light (1: one blurred "
                            "frame; the cost grows about linearly)")
