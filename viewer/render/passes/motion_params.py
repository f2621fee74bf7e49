"""Parameters of how every real-time mode samples the motion over the exposure: one
`@group("motion")` read by the renderer around any pipeline (viewer/render/steps.py), and
the `curve_steps` field each real-time mode's own group carries (its default is the
mode's: the published filters keep their linear behaviour, the hybrid follows curves)."""
from __future__ import annotations

from viewer.render.graph.params import group, param

MAX_STEPS = 256
MAX_CURVE_STEPS = 16


@group("motion")
class MotionParams:
    steps: int = param(1, lo=1, hi=MAX_STEPS,
                       help="sub-exposure steps: the frame as this many sub-frames at the "
                            "centres of equal parts of the exposure, each blurred by the "
                            "mode over its part, averaged in linear light (1: one blurred "
                            "frame; the cost grows about linearly)")
    curve_px: float = param(1.0, unit="px", lo=0.01, hi=1000.0,
                            help="a mode's curve_steps start where some visible surface "
                                 "point's screen path strays more than this from uniform "
                                 "motion along its chord (rotation, approach, "
                                 "acceleration, a bounce; world/path_bend.py)")


def curve_steps_param(default: int):
    """The `curve_steps` field of a real-time mode's parameters."""
    return param(default, unit="steps", lo=1, hi=MAX_CURVE_STEPS,
                 help="sub-exposure steps taken where the motion bends (its screen paths "
                      "stray more than motion.curve_px from their chords): "
                      "ceil(sqrt(bend / curve_px)) sub-frames, at least 2, at most this "
                      "many; 1 = one linear blur always (motion.steps still applies: the "
                      "larger count is taken)")
