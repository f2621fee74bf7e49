"""Mode `reference`: the mean of N sharp frames at the stratified times of the contract,
averaged in unclamped linear colour (clamped once, at encoding). Optionally records every
sub-frame's object ids and depths, from which the evaluation regions are classified."""
from __future__ import annotations

import numpy as np

from viewer.render.graph.params import group, param
from viewer.render.modes.regions import RegionAccumulator
from viewer.render.graph.frame import Frame
from viewer.render.passes.gbuffer import STATIC_RASTER_READ, GBufferPass
from viewer.render.graph.host import HostResource
from viewer.render.graph.registry import NoConfig, mode
from viewer.render.graph.passes import FullscreenPass, Pass, Pipeline
from viewer.render.graph.pool import ReadBack, TexSpec


@group("reference")
class ReferenceParams:
    samples: int = param(64, unit="sub-frames", lo=1, hi=4096, help="sharp sub-frames averaged over the exposure")


# The evaluation region of every pixel (viewer/render/modes/regions.py codes, image rows), made only
# where the frame asks for it (Frame.record_visibility).
REGIONS = HostResource("regions", np.ndarray, "evaluation region per pixel")


class Accumulate(FullscreenPass):
    fragment = "passes/accumulate.frag"


class ReferencePass(Pass):
    name = "reference"
    inputs = ("id", "depth")
    host_outputs = (REGIONS,)
    # The regions: the frame time's visibility and every sub-frame's, read back.
    reads_back = (*(ReadBack(n, "recording visibility (compare)")
                    for n in ("id", "depth", "sub_id", "sub_depth")), STATIC_RASTER_READ)

    def __init__(self):
        self.sub_color = GBufferPass(prefix="sub_", layout="color")
        self.sub_visibility = GBufferPass(prefix="sub_", layout="visibility")
        self.acc = Accumulate()
        # The sub-frames' G-buffer targets, drawn by this pass (the visibility's when
        # recording it).
        self.produces = ("reference", *self.sub_visibility.produces)

    def outputs(self, frame: Frame):
        return {"reference": TexSpec(4, "f4")}

    def execute(self, frame: Frame):
        n = frame.params["reference"].samples
        if frame.shutter == 0:
            n = 1    # N identical sub-frames: their mean is the frame itself, exactly
        fbo = frame.pool.framebuffer(("reference",))
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        # Regions (docs/algorithms.md 5.3) from every sub-frame's visibility against the frame
        # time's G-buffer, streamed so no stack of N id buffers is kept.
        regions = (RegionAccumulator(frame.read("id"), frame.read("depth"))
                   if frame.record_visibility else None)
        sub = self.sub_color if regions is None else self.sub_visibility
        sub.allocate(frame)
        progress = frame.progress
        for k, tk in enumerate(frame.sample_times(n)):
            if progress is not None:
                progress(k, n)
            sub.execute(frame, time=float(tk))
            self.acc.draw(frame, ("reference",), {"u_src": "sub_color"},
                          {"u_weight": 1.0 / n}, blend=True)
            if regions is not None:
                regions.add(frame.read("sub_id"), frame.read("sub_depth"))
        if regions is not None:
            frame.host.put(REGIONS, regions.result())
        frame.stats["samples"] = n

    # Progressive accumulation (the viewer): the same sub-frames, weights and blending order
    # as execute() without regions, spread over several calls, so the finished mean is the
    # same image. start() clears the running sum; accumulate() adds sub-frames k0 .. k0+n-1.
    def total(self, frame: Frame) -> int:
        return frame.params["reference"].samples

    def start(self, frame: Frame):
        self.allocate(frame)
        self.sub_color.allocate(frame)
        fbo = frame.pool.framebuffer(("reference",))
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0)

    def accumulate(self, frame: Frame, first: int, count: int) -> int:
        """Add sub-frames first .. first+count-1 of N (each weighted 1/N); returns how many
        of the N are in the sum afterwards."""
        n = self.total(frame)
        self.sub_color.allocate(frame)
        last = min(n, first + max(0, count))
        for tk in frame.sample_times(n)[first:last]:
            self.sub_color.execute(frame, time=float(tk))
            self.acc.draw(frame, ("reference",), {"u_src": "sub_color"},
                          {"u_weight": 1.0 / n}, blend=True)
        frame.stats["samples"] = last
        return last


@mode("reference", groups=("reference",), steps=False)
def reference_pipeline(config: NoConfig = NoConfig()) -> Pipeline:
    return Pipeline("reference", [GBufferPass(), ReferencePass()], output="reference",
                    config=config)
