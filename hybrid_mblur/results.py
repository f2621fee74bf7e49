"""What the API's renders return: images as arrays (linear float RGB and sRGB 8-bit, top
row first), the mode's buffers on request, and the reference with its blur regions."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from viewer.io.imageio import linear_to_srgb8
from viewer.render.modes.regions import NAMES

__all__ = ["Render", "Reference"]


@dataclass
class Render:
    """One frame of one mode (or user pass).

    `image`: linear RGB, float32 (H, W, 3), row 0 the top row, unclamped; `srgb`: the 8-bit
    sRGB codes `hmblur shot` writes to its PNG; `buffers`: with render(buffers=True), every
    texture the frame made, by name, in pipeline order (image orientation; vectors in GL
    axes; docs/api.md lists them); `stats`, `pass_ms`: the frame's counters and pass times."""
    mode: str
    image: np.ndarray
    time: float
    seed: int
    buffers: dict[str, np.ndarray] = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    pass_ms: dict = field(default_factory=dict)

    @property
    def srgb(self) -> np.ndarray:
        """(H, W, 3) uint8 sRGB, as written to PNG files."""
        return linear_to_srgb8(self.image)

    @property
    def size(self) -> tuple[int, int]:
        """(W, H) in pixels."""
        return self.image.shape[1], self.image.shape[0]


@dataclass
class Reference(Render):
    """The ground truth (mode "reference": the mean of reference.samples sub-frames over
    the exposure) with its blur regions: `regions` (H, W) uint8, 0 static, 1 inner, 2 outer
    (viewer/render/modes/regions.py)."""
    regions: np.ndarray | None = None

    def masks(self) -> dict[str, np.ndarray]:
        """{"all", "static", "inner", "outer"}: boolean (H, W) masks of the regions."""
        out = {"all": np.ones(self.regions.shape, dtype=bool)}
        out.update({name: self.regions == code for code, name in NAMES.items()})
        return out
