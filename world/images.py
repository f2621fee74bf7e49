"""Image textures as the renderers take them: linear RGB, float32, (H, W, 3), top row first.

The program's one sRGB decoding (IEC 61966-2-1): scene files' image textures
(world/loader.py), glTF base-colour images (world/gltf/reader.py) and the viewer's 8-bit
images (viewer/imageio.py) all decode through it.
"""
from __future__ import annotations

import numpy as np
from PIL import Image


def srgb_to_linear(c) -> np.ndarray:
    """The standard sRGB decoding of values in [0, 1], float64."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


# The linear value of each 8-bit code, as float32: 8-bit images decode through this table
# (the same values as srgb_to_linear(code / 255), without a float64 copy of the image).
SRGB8_LINEAR = srgb_to_linear(np.arange(256) / 255.0).astype(np.float32)
SRGB8_LINEAR.flags.writeable = False

# Pillow's single-channel modes wider than 8 bits, and their full scale: convert("RGB")
# would clip them to 255 (a 16-bit grey PNG opens as "I;16", or "I" in older Pillows).
WIDE_GREY = {"I;16": 65535.0, "I;16L": 65535.0, "I;16B": 65535.0, "I;16N": 65535.0,
             "I": 65535.0, "F": 1.0}


def srgb8_to_linear(codes) -> np.ndarray:
    """8-bit sRGB codes (any shape) -> float32 linear."""
    return SRGB8_LINEAR[np.asarray(codes)]


def linear_rgb(im: Image.Image) -> np.ndarray:
    """An opened image's linear RGB, (H, W, 3) float32: 8-bit modes through Pillow's RGB
    conversion (alpha dropped, palettes expanded) and the 256-entry table; wide grey at
    its own precision."""
    scale = WIDE_GREY.get(im.mode)
    if scale is None:
        return srgb8_to_linear(np.asarray(im.convert("RGB")))
    grey = np.clip(np.asarray(im, dtype=np.float64) / scale, 0.0, 1.0)
    return np.repeat(srgb_to_linear(grey).astype(np.float32)[..., None], 3, axis=-1)
