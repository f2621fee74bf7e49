"""Regenerates scenes/assets/: a small painting (PNG, sRGB) and the quad it hangs on (OBJ
with UVs). Run `python -m scenes.make_assets`; the outputs are committed, so the scenes do
not depend on this script at load time.

The painting is a sunset over hills with a bright sun and a striped field: high-contrast
edges, so a blur that drags the wrong pixels over it is easy to see.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

ASSETS = Path(__file__).resolve().parent / "assets"


def painting(width: int = 120, height: int = 80) -> np.ndarray:
    """(height, width, 3) uint8 sRGB, top row first."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    u, v = (x + 0.5) / width, (y + 0.5) / height          # v = 0 at the top
    sky_top, sky_low = np.array([40, 60, 140]), np.array([250, 170, 90])
    img = sky_top + (sky_low - sky_top) * np.minimum(v / 0.62, 1.0)[..., None]
    sun = (u - 0.68) ** 2 + ((v - 0.42) * height / width) ** 2 < 0.09 ** 2
    img[sun] = [255, 235, 120]
    far_hill = v > 0.55 + 0.08 * np.sin(u * 7.0 + 1.0)
    img[far_hill] = [70, 50, 110]
    near_hill = v > 0.68 + 0.06 * np.sin(u * 11.0 - 0.5)
    img[near_hill] = [30, 90, 50]
    field = v > 0.82
    img[field] = np.where((np.floor(u * 12 + v * 6) % 2 == 0)[field][:, None],
                          [200, 180, 40], [120, 40, 30])
    border = (x < 2) | (x >= width - 2) | (y < 2) | (y >= height - 2)
    img[border] = [245, 240, 225]                           # a mat inside the frame
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


QUAD_OBJ = """\
# A unit quad in the XY plane facing +Z, centred on the origin, with UVs covering the image
# once (origin at the image's bottom-left, as trimesh returns them).
v -0.5 -0.5 0.0
v 0.5 -0.5 0.0
v 0.5 0.5 0.0
v -0.5 0.5 0.0
vt 0.0 0.0
vt 1.0 0.0
vt 1.0 1.0
vt 0.0 1.0
vn 0.0 0.0 1.0
f 1/1/1 2/2/1 3/3/1
f 1/1/1 3/3/1 4/4/1
"""


def main() -> None:
    ASSETS.mkdir(exist_ok=True)
    Image.fromarray(painting()).save(ASSETS / "painting.png", optimize=True)
    (ASSETS / "quad_uv.obj").write_text(QUAD_OBJ)


if __name__ == "__main__":
    main()
