"""Progressive rendering of a mode whose pipeline has an accumulating pass (the reference):
a few sub-frames per displayed frame into the running sum, restarting when anything that
changes the image changes. When all N sub-frames are in, the sum is the image
`Renderer.render` gives (same sub-frames, weights and blending order)."""
from __future__ import annotations

from viewer.render.graph.params import ParamSet
from viewer.render.graph.frame import Frame
from ..render.renderer import Renderer
from viewer.render.timing import PassClock


def accumulating_pass(pipeline):
    """The pass that offers start/accumulate/total, or None."""
    for p in pipeline.passes:
        if all(hasattr(p, a) for a in ("start", "accumulate", "total")):
            return p
    return None


class Progressive:
    def __init__(self):
        self.key = None
        self.done = 0
        self.total = 0

    def reset(self):
        self.key = None

    @property
    def gain(self) -> float:
        """What the partial sum (each sub-frame weighted 1/N) is multiplied by to show the
        mean of the sub-frames so far."""
        return self.total / self.done if self.done else 0.0

    def step(self, clock: PassClock, renderer: Renderer, mode: str, t: float, params: ParamSet,
             seed: int, key, per_frame: int) -> Frame:
        """Add up to `per_frame` sub-frames; start over first when `key` differs from the
        last call's (it must capture everything the image depends on)."""
        pipe = renderer.pipeline(mode, params)
        acc = accumulating_pass(pipe)
        frame = clock.frame(renderer, t, params, seed)
        index = pipe.passes.index(acc)
        if key != self.key:
            self.key, self.done = None, 0
            pipe.run(frame, clock.measure, stop=index)   # e.g. the frame-time G-buffer, once
            with clock.measure(frame, acc.name):
                acc.start(frame)
            self.key = key
        self.total = acc.total(frame)
        if self.done < self.total:
            with clock.measure(frame, acc.name):
                self.done = acc.accumulate(frame, self.done, per_frame)
        pipe.run(frame, clock.measure, start=index + 1)
        frame.stats.update(sub_frames=f"{self.done}/{self.total}")
        return frame
