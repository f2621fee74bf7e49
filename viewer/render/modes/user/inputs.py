"""What a user's blur pass reads and writes: the same buffers under the same names for both
kinds, as GLSL samplers (u_NAME) and as fields of BlurInputs (numpy, image orientation).

Every buffer is the frame's G-buffer (layout "full": viewer/render/passes/gbuffer.py) or a
tile reduction of its displacement (viewer/render/passes/tiles.py); docs/api.md documents
them for users."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Pool texture -> the name a user reads it by (sampler u_NAME, BlurInputs.NAME).
TEXTURES = {
    "color": "color",                 # linear RGB of the sharp frame at t (a = 1)
    "depth": "depth",                 # linear view depth, metres
    "velocity": "velocity",           # displacement over the exposure, px, GL axes
    "id": "id",                       # object id, 0 = background (unsigned)
    "normal": "normal",               # world normal, facing the camera
    "user_tilemax": "tilemax",        # per tile of k x k px: the displacement of largest length
    "user_neighbormax": "neighbormax",  # per tile: the largest tilemax of the 3 x 3 around it
}
INPUT_TEXTURES = tuple(TEXTURES)
SAMPLERS = {f"u_{user}": pool for pool, user in TEXTURES.items()}
OUTPUT = "user"                       # the pass's output texture: linear RGB (a = 1)
TILE_PREFIX = "user"                  # user_tilemax_x, user_tilemax, user_neighbormax
# The parameter groups a user pass reads: the blur limit k (its tile size) and the
# sub-exposure steps every real-time blur takes (viewer/render/steps.py).
USER_GROUPS = ("blur", "motion")


@dataclass(frozen=True)
class BlurInputs:
    """A Python blur pass's one argument. Arrays are image orientation (row 0 is the top
    row), float32 unless said; vectors are in pixels, GL axes (x to the right, y up: a
    displacement (dx, dy) moves a point from image row r to row r - dy)."""
    color: np.ndarray          # (H, W, 3) linear RGB of the sharp frame at `time`
    depth: np.ndarray          # (H, W) linear view depth in metres (background: 1e9)
    velocity: np.ndarray       # (H, W, 2) screen displacement over the exposure D, not clamped
    id: np.ndarray             # (H, W) uint32 object id, 0 = background
    normal: np.ndarray         # (H, W, 3) world normal facing the camera
    tilemax: np.ndarray        # (ceil(H/k), ceil(W/k), 2): per tile, the D of largest length
    neighbormax: np.ndarray    # same shape: per tile, the largest tilemax of the 3 x 3 around it
    tile: int                  # k: the tile size and blur limit in pixels (blur.max_radius)
    exposure: float            # the shutter in seconds (this sub-frame's, with motion.steps)
    time: float                # the frame time in seconds
    seed: int                  # the frame's seed (jitter keyed by it stays deterministic)

    @property
    def size(self) -> tuple[int, int]:
        """(W, H) in pixels."""
        return self.color.shape[1], self.color.shape[0]

    def tile_of(self, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(tile row, tile column) into tilemax / neighbormax of image pixels (rows, cols):
        tiles are counted from the bottom-left corner (GL), so the top row of tiles may be
        partial."""
        h = self.color.shape[0]
        th = self.tilemax.shape[0]
        return th - 1 - (h - 1 - np.asarray(rows)) // self.tile, np.asarray(cols) // self.tile
