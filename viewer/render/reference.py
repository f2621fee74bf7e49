"""Mode `reference`: the mean of N sharp frames at the stratified times of the contract,
averaged in unclamped linear colour (clamped once, at encoding). Optionally records every
sub-frame's object ids and depths, from which the evaluation regions are classified."""
from __future__ import annotations

import numpy as np

from ..params import group, param
from .frame import Frame
from .gbuffer import GBufferPass
from .modes import mode
from .passes import FullscreenPass, Pass, Pipeline
from .pool import TexSpec


@group("reference")
class ReferenceParams:
    samples: int = param(64, lo=1, hi=4096, help="sharp sub-frames averaged over the exposure")


class Accumulate(FullscreenPass):
    fragment = "accumulate.frag"


class ReferencePass(Pass):
    name = "reference"
    inputs = ("id", "depth")
    produces = ("reference",)

    def __init__(self):
        self.sub = GBufferPass(prefix="sub_")
        self.acc = Accumulate()

    def outputs(self, frame: Frame):
        return {"reference": TexSpec(4, "f4")}

    def execute(self, frame: Frame):
        n = frame.params["reference"].samples
        self.sub.allocate(frame)
        fbo = frame.pool.framebuffer(("reference",))
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        record = frame.host.get("record_visibility", False)
        ids, depths = [], []
        for tk in frame.scene.sample_times(frame.time, n):
            self.sub.execute(frame, time=float(tk))
            self.acc.draw(frame, ("reference",), {"u_src": "sub_color"},
                          {"u_weight": 1.0 / n}, blend=True)
            if record:
                ids.append(frame.read("sub_id"))
                depths.append(frame.read("sub_depth"))
        if record:
            frame.host["sample_ids"] = np.stack(ids)
            frame.host["sample_depths"] = np.stack(depths)
        frame.stats["samples"] = n


@mode("reference", groups=("reference",))
def reference_pipeline() -> Pipeline:
    return Pipeline("reference", [GBufferPass(), ReferencePass()], output="reference")
