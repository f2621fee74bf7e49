"""Sub-exposure steps (`--set motion.steps=N`), around any real-time mode's pipeline.

The frame at time t with shutter s is rendered as N sub-frames, sub-frame k at the centre
t_k = t - s/2 + (k + 0.5) s/N of the k-th of N equal parts of the exposure
(conventions.sample_times), each a whole run of the mode's pipeline on a Frame whose
shutter is s/N, so that the mode blurs over its part only; the N images are averaged in
linear light, unclamped (an f4 sum of the first N - 1 images, added in k order by the
GPU's blending, then (1/N) (sum + image_N-1) blended into the pipeline's output
texture), where every reader (the CLI, the viewer, `--buffers`) finds the image as usual.
Each linear blur then follows one N-th of the path, so motion that bends, turns or speeds
up within the exposure is followed by N chords instead of one.

N = 1 is the plain frame (no sub-frame, no copy: the image is today's to the bit); a zero
shutter is too (N sub-frames at one time show the same image). A mode takes steps when it
lists the "motion" group (viewer/render/modes/__init__.py: every mode but `off`, a sharp frame, and
`reference`, which has its own samples).

Seeds: sub-frame k of a frame with seed S is jittered with seed S * N + k, so the N
sub-frames' noise differs (glsl/graph/noise.glsl keys every jitter by the seed) and is the same
on every run; two seeds' sub-frames never share one (S * N .. S * N + N - 1 are disjoint);
N = 1 keeps S.

What the returned Frame reports: the image's time, shutter and seed; `stats` summed over
the sub-frames where numeric (masked pixels, rays, tiles drawn, the reveal's ms: the whole
frame's work), else the last sub-frame's, and `steps` = N; `pass_ms` / `pass_cpu_ms`
summed per pass over the sub-frames, with the accumulation as pass `motion_steps`; `host`
the last sub-frame's (its tile lists, masked pixels, ...). The G-buffer and every other
intermediate texture in the pool hold the last sub-frame's.

State kept across frames (the hybrid's Embree poses, static layer, tile records) is keyed
by what it was made from (matrices, views, written tiles), never by the frame's time, so
sub-frames at other times and shutters find it correct: a sub-frame is a frame.
"""
from __future__ import annotations

import dataclasses
import math
import numbers
from contextlib import AbstractContextManager
from typing import Callable

import moderngl

from world import conventions
from viewer.render.graph.params import ParamSet
from viewer.render.graph.frame import Frame, PassTimer
from viewer.render.modes import MODE_GROUPS
from viewer.render.passes.motion_params import MotionParams  # noqa: F401  (registers the "motion" group)
from viewer.render.graph.passes import FullscreenPass, Pipeline
from viewer.render.graph.pool import TexSpec

GROUP = "motion"
SUM = "motion_steps_sum"           # the running sum of the sub-frames (f4, unclamped)
PASS_NAME = "motion_steps"         # the accumulation's entry in pass_ms


class Accumulate(FullscreenPass):
    name = PASS_NAME
    fragment = "passes/accumulate.frag"       # target += weight * source (with additive blending)


class Mean(FullscreenPass):
    name = PASS_NAME
    fragment = "passes/steps_mean.frag"       # target = weight * (source + target), blended


_ACC = Accumulate()
_MEAN = Mean()
# rgb: src + dst * src.a (the shader's alpha is the weight); alpha: the target's kept
MEAN_BLEND = (moderngl.ONE, moderngl.SRC_ALPHA, moderngl.ZERO, moderngl.ONE)


def curve_steps(bend_px: float, curve_px: float, most: int) -> int:
    """Sub-frames for a path that strays `bend_px` from its chord: 1 within `curve_px`,
    else enough that each sub-exposure strays about curve_px (1/N^2 of the bend:
    world/path_bend.py), at least 2 and at most `most`."""
    if most <= 1 or bend_px <= curve_px:
        return 1
    return int(min(most, max(2, math.ceil(math.sqrt(bend_px / curve_px)))))


SCENE_POSE = "scene_pose"          # the glTF entries' poses at the frame's times (host)
BEND = "motion_bend"               # how far the frame's screen paths bend (host)


def most_curve_steps(mode: str, params: ParamSet, groups: tuple[str, ...] | None = None
                     ) -> int:
    """The sub-frames `mode` takes where motion bends: its curve_steps, 1 for a mode that
    follows curves within the frame (hybrid.curve = inverse) or takes none."""
    groups = MODE_GROUPS.get(mode, ()) if groups is None else groups
    own = params[mode] if mode in groups else None
    return (int(getattr(own, "curve_steps", 1))
            if own is not None and getattr(own, "curve", "steps") == "steps" else 1)


def around(mode: str, params: ParamSet) -> list[tuple[str, str, str]]:
    """The work Renderer.run does around `mode`'s pipeline under `params`, as `hmblur
    bench` times it: (name, "cpu" or "gpu", when it runs)."""
    rows = [(SCENE_POSE, "cpu", "where the scene has glTF entries: their node matrices and "
                                "skinned vertices at the frame's times, once a frame")]
    if GROUP not in MODE_GROUPS.get(mode, ()):
        return rows
    n, most = int(params[GROUP].steps), most_curve_steps(mode, params)
    if most > n:
        rows.append((BEND, "cpu", f"how far the screen paths bend (world/path_bend.py): "
                                  f"up to {most} sub-frames where more than "
                                  f"motion.curve_px"))
    if max(n, most) > 1:
        rows.append((PASS_NAME, "gpu", "the sub-frames' average in linear light"
                                       + ("" if n > 1 else ", where the motion bends")))
    return rows


def step_count(mode: str, params: ParamSet, shutter: float,
               bend: Callable[[], float] = lambda: 0.0,
               groups: tuple[str, ...] | None = None) -> int:
    """How many sub-frames `mode` renders under `params` for an exposure of `shutter`:
    motion.steps, or the mode's curve_steps where the motion bends (unless it follows
    curves within the frame), whichever is more.
    `bend()` is the frame's screen_bend (px), asked for only where it can matter;
    `groups`: the mode's parameter groups (default: the registry's; a user pass's are the
    renderer's)."""
    groups = MODE_GROUPS.get(mode, ()) if groups is None else groups
    if GROUP not in groups or shutter == 0:
        return 1
    n = int(params[GROUP].steps)
    most = most_curve_steps(mode, params, groups)
    if most > n:
        n = max(n, curve_steps(bend(), float(params[GROUP].curve_px), most))
    return n


def step_seed(seed: int, n: int, k: int) -> int:
    return seed * n + k


def sub_exposures(t: float, shutter: float, seed: int, n: int
                  ) -> list[tuple[float, float, int]]:
    """(time, shutter, seed) of each of the n sub-frames, in order."""
    if n == 1:
        return [(t, shutter, seed)]
    times = conventions.sample_times(t, shutter, n)
    return [(float(tk), shutter / n, step_seed(seed, n, k)) for k, tk in enumerate(times)]


MakeFrame = Callable[[float, float, int], Frame]      # (time, shutter, seed) -> a new Frame
Measure = Callable[[Frame, str], AbstractContextManager]


def run_steps(make_frame: MakeFrame, pipeline: Pipeline, t: float, shutter: float,
              seed: int, n: int, measure: Measure = PassTimer) -> Frame:
    """Render the frame at t as n sub-frames (module doc): `make_frame` makes each
    sub-frame's Frame, the pipeline runs on it with every pass and the accumulation inside
    `measure(frame, name)`. Returns the whole frame's Frame."""
    subs = sub_exposures(t, shutter, seed, n)
    output = pipeline.output
    if n == 1:
        frame = make_frame(*subs[0])
        pipeline.run(frame, measure=measure)
        return frame
    stats: dict = {}
    pass_ms: dict = {}
    pass_cpu_ms: dict = {}
    weight = 1.0 / n
    for k, (tk, sk, seed_k) in enumerate(subs):
        frame = make_frame(tk, sk, seed_k)
        pipeline.run(frame, measure=measure)
        with measure(frame, PASS_NAME):
            # SUM = o_0 + ... + o_{n-2} (the first copied, the others added by blending);
            # the last sub-frame's output then becomes w SUM + w o_{n-1} in place, by
            # blending: one full-screen draw a sub-frame (n = 2: a copy and one draw).
            if k == 0:
                frame.pool.texture(SUM, TexSpec(4, "f4"))
                frame.ctx.copy_framebuffer(frame.pool.framebuffer((SUM,)),
                                           frame.pool.framebuffer((output,)))
                frame.pool.mark_written((SUM,), None)
            elif k < n - 1:
                _ACC.draw(frame, (SUM,), {"u_src": output}, {"u_weight": 1.0}, blend=True)
            else:
                _MEAN.draw(frame, (output,), {"u_src": SUM}, {"u_weight": weight},
                           blend=MEAN_BLEND)
        _add(stats, frame.stats)
        _add(pass_ms, frame.pass_ms)
        _add(pass_cpu_ms, frame.pass_cpu_ms)
    stats["steps"] = n
    return dataclasses.replace(frame, time=t, shutter=shutter, seed=seed, stats=stats,
                               pass_ms=pass_ms, pass_cpu_ms=pass_cpu_ms)


def _add(total: dict, one: dict):
    """Numbers summed into `total`; anything else (a label) replaced by the latest."""
    for key, value in one.items():
        have = total.get(key)
        total[key] = have + value if _number(value) and _number(have) else value


def _number(x) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool)
