"""Parameters of the hybrid mode (docs/algorithms.md 4), one `@group("hybrid")` shared by the ray
mask, the reveal and the composite passes (each module imports it, so a ParamSet made after
importing any of them has the group)."""
from __future__ import annotations

from viewer.render.graph.params import group, param
from viewer.render.passes.gbuffer import SEGMENT_CHOICES
from viewer.render.passes.motion_params import curve_steps_param

COMPOSITES = ("bucket", "split", "time")
CURVES = ("inverse", "steps")


@group("hybrid")
class HybridParams:
    # ---- motion (viewer/render/passes/gbuffer.py, glsl/passes/path.glsl)
    # 1 by default: at 640x360 2 segments cost 2.3-3.1x McGuire's frame (4: 3.1-4.8x), for
    # whole-image FLIP 0.59-1.08x the linear blur's; curve steps give 0.27-0.83x at
    # 1.95-2.6x (docs/performance.md "Bending motion").
    segments: int = param(1, unit="segments", choices=SEGMENT_CHOICES, effect="recompile",
                          help="linear pieces of each pixel's screen path over the "
                               "exposure (its points projected at evenly spaced times): "
                               "tiles, ray mask and composite follow the path; 1 = the "
                               "chord alone (the paper). Helps where objects roll, arc or "
                               "bounce as a whole (wheel, keys_arc: 4 best); no help "
                               "where a body turns about a point off it (turning_car, "
                               "spinner, rover: what passes a pixel is gathered along "
                               "one path per tile, and a turn's paths turn across the "
                               "tile); each about doubles the composite; curve_steps "
                               "(the default) gives less error on every bending scene "
                               "measured, at a similar or lower cost")
    # 2 where the motion bends (viewer/render/steps.py): whole-image FLIP 0.27-0.63x the
    # linear blur's on wheel, spinner, keys_arc, rover, basic, turning_car, where path
    # segments reach 0.59-1.08x (docs/performance.md); straight motion stays one frame.
    curve_steps: int = curve_steps_param(2)
    curve: str = param("steps", choices=CURVES, effect="recompile",
                       help="how motion that bends (more than motion.curve_px) is "
                            "followed: steps (default), curve_steps sub-frames, each a "
                            "whole frame; inverse, in one frame, each pixel's time "
                            "samples mapped back along every candidate object's exact "
                            "motion (docs/algorithms.md 6.1) on the tiles movers reach: "
                            "less error where bodies turn fast (fan 0.63x, turning_car "
                            "0.76x, spinner 0.88x the steps' whole-image FLIP), more "
                            "where a straight mover or a moving camera gains from two "
                            "sub-frames (keys_arc, basic, shapes, rover), at 2-5.6x "
                            "McGuire's frame against the steps' 1.9-2.7x on software GL "
                            "(docs/performance.md)")
    curve_samples: int = param(32, unit="times", lo=1, hi=64,
                               help="curve = inverse: the times of the exposure (centres "
                                    "of equal parts) at which every mover's and the "
                                    "camera's pose is taken; a pixel's time samples are "
                                    "stratified over them")
    time_samples: int = param(8, unit="samples", lo=1, hi=64,
                              help="curve = inverse: times of the exposure sampled per "
                                   "pixel where motion bends, at most (one per "
                                   "sample_spacing px of the motion near the pixel; "
                                   "stratified, jittered per pixel)")
    depth_tolerance: float = param(0.02, unit="fraction of the depth", lo=0.0, hi=0.5,
                                   help="curve = inverse: a candidate covers a time sample "
                                        "where its surface lies on the pixel's ray within "
                                        "this fraction of its depth (or maps back within "
                                        "`tolerance` px)")
    # ---- ray mask (viewer/render/modes/hybrid/mask.py)
    min_speed: float = param(1.0, unit="px", lo=0.0, hi=64.0,
                             help="displacement over the exposure (px) below which a pixel "
                                  "counts as still and is never masked")
    depth_threshold: float = param(0.01, unit="fraction of the depth", lo=0.0, hi=1.0,
                                   help="displacement test: the displaced position must be "
                                        "farther by this fraction of the pixel's depth")
    edge_depth: float = param(0.05, unit="log-depth step", lo=0.0, hi=10.0,
                              help="Sobel threshold on log depth (a step of ~5% per pixel "
                                   "at 0.05; the kernel is normalised to step units; log "
                                   "depth is kept at half precision, steps of ~0.1%)")
    edge_normal: float = param(0.3, unit="normal step", lo=0.0, hi=4.0,
                               help="Sobel threshold on the world normal (vector step units)")
    range_check: bool = param(False,
                              help="ray mask: on, the poster's three steps (the "
                                   "displacement test, then a Sobel edge test on its "
                                   "survivors, then a range check along each pixel's "
                                   "displacement from those edges); off (default), the "
                                   "pixels whose hidden background shows at some time "
                                   "(probes along the displacement relative to the "
                                   "background): the same mask under a still camera, "
                                   "far fewer rays under a moving one (pan: 1.7 k to 39 "
                                   "k; inner FLIP .052 to .048; docs/performance.md)")
    relative_reach: float = param(2.0, unit="half displacements", lo=1.0, hi=8.0,
                                  help="range check: search this many half displacements "
                                       "along the velocity (> 1 finds the wider band that "
                                       "opens when the background moves the other way)")
    # ---- ray reveal (viewer/render/modes/hybrid/reveal.py)
    trace: bool = param(True, help="cast the masked pixels' rays; off leaves the revealed "
                                   "layer empty (the composite alone, for comparison)")
    max_depth: int = param(8, unit="restarts", lo=0, hi=64,
                           help="restarts allowed to pass through the pixel's own static "
                                "object (recursion depth of the reveal)")
    threads: int = param(0, unit="threads", lo=0, hi=64,
                         help="ray-tracing threads for large batches (0 = CPU count)")
    # ---- composite (viewer/render/modes/hybrid/composite.py)
    composite: str = param("bucket", choices=COMPOSITES, effect="recompile",
                           help="bucket: fragments gathered along lines, sorted by object "
                                "and depth, combined front to back, background taps paired "
                                "with their times (docs/algorithms.md 4.3; as cheap as McGuire's "
                                "gather); time: per-pixel time samples resolve visibility "
                                "between the raster and revealed layers (best, 8-10x "
                                "costlier); split: time near the ray mask, bucket elsewhere "
                                "(docs/performance.md)")
    samples_min: int = param(8, unit="samples", lo=1, hi=256,
                             help="time samples per pixel (bucket: taps per line) where "
                                  "anything moves, at least")
    samples_max: int = param(16, unit="samples", lo=1, hi=256,
                             help="time samples per pixel (bucket: taps per line), at most")
    sample_spacing: float = param(2.0, unit="px per sample", lo=0.25, hi=16.0,
                                  help="pixels of motion per time sample or tap: the count "
                                       "grows with the displacement")
    jitter: float = param(1.0, unit="fraction of a step", lo=0.0, hi=1.0,
                          help="per-pixel jitter of the stratified times or taps: 0 = "
                               "fixed (banding), 1 = one offset per pixel (noise: "
                               "random for the time composite, interleaved gradient "
                               "noise for the bucketed one)")
    seeds: int = param(2, unit="tile maxima", lo=1, hi=9, effect="recompile",
                       help="distinct tile maxima around a pixel whose surfaces are looked "
                            "for at each time sample (what may pass over it)")
    iterations: int = param(3, unit="iterations", lo=0, hi=8,
                            help="fixed-point refinements mapping a pixel back to the "
                                 "frame time along a surface's own velocity")
    tolerance: float = param(0.65, unit="px", lo=0.5, hi=2.0,
                             help="a surface covers the pixel at a time sample when it "
                                  "lands within this many pixels (Chebyshev) of its centre")
