"""Image textures as the renderers take them: linear RGB, float32, (H, W, 3), top row first.

The program's one sRGB decoding (IEC 61966-2-1): scene files' image textures
(world/loader.py) and glTF base-colour images (world/gltf/reader.py) both decode through
it.

A scene's images are decoded by one SceneImages: each distinct content once (files with
the same bytes, glTF images named by several materials), shared read-only, every texel it
holds counted against limits.MAX_SCENE_IMAGE_PIXELS, each image's size checked from its
header before it is decoded. Decoding holds the decoder's own pixels and the float32
result, no more: rows are converted a strip at a time. The texels are stored bottom row
first (GL's row order, which the upload wants) and handed out as the top-down view.
"""
from __future__ import annotations

import hashlib
import io
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from world import limits
from world.scene import Texture


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

STRIP_PIXELS = 1 << 16       # pixels converted at a time


def linear_rgb(im: Image.Image) -> np.ndarray:
    """An opened image's linear RGB, (H, W, 3) float32, top row first: 8-bit modes through
    Pillow's RGB conversion (alpha dropped, palettes expanded) and the 256-entry table;
    wide grey at its own precision. Stored bottom row first (a read-only view)."""
    w, h = im.size
    gl_rows = np.empty((h, w, 3), np.float32)
    scale = WIDE_GREY.get(im.mode)
    step = max(1, STRIP_PIXELS // max(w, 1))
    for y in range(0, h, step):
        y1 = min(h, y + step)
        strip = im.crop((0, y, w, y1))
        out = gl_rows[h - y1: h - y]          # the same rows, bottom row first
        if scale is None:                   # (mode "clip": uint8 codes, no bounds buffer)
            np.take(SRGB8_LINEAR, np.asarray(strip.convert("RGB"))[::-1], out=out, mode="clip")
        else:
            grey = np.clip(np.asarray(strip, dtype=np.float64)[::-1] / scale, 0.0, 1.0)
            out[...] = srgb_to_linear(grey).astype(np.float32)[..., None]
    image = gl_rows[::-1]
    image.flags.writeable = False
    return image


class ImageError(Exception):
    """What is wrong with an image, in one line (the caller names the file and key)."""


def _undecodable(e: Exception) -> ImageError:
    """The reason in the user's words, not Pillow's: not an image format it reads, or an
    image whose data is damaged or cut short."""
    if isinstance(e, UnidentifiedImageError):
        return ImageError("cannot decode the image: not an image file Pillow reads "
                          "(PNG, JPEG, ...)")
    return ImageError("cannot decode the image: its data is damaged or cut short")


class _Decoded:
    def __init__(self, texels: np.ndarray, fmt: str | None):
        self.texels, self.format = texels, fmt


class SceneImages:
    """One scene's decoded images, each distinct content decoded once, and the image
    Textures drawing them, one per texel array (the renderer uploads each Texture once)."""

    def __init__(self):
        self.pixels = 0                                   # held, against the scene's limit
        self._decoded: dict[bytes, _Decoded] = {}         # by SHA-256 of the file's bytes
        self._tinted: dict[tuple[int, bytes], np.ndarray] = {}
        self._textures: dict[int, Texture] = {}

    def from_file(self, path: Path) -> np.ndarray:
        """The texels of an image file (any format Pillow reads)."""
        digest = hashlib.sha256()
        try:
            with open(path, "rb") as f:
                for block in iter(lambda: f.read(1 << 20), b""):
                    digest.update(block)
        except OSError as e:
            raise ImageError(f"cannot read it ({e.strerror or e})") from None
        return self._texels(digest.digest(), lambda: Image.open(path), None)

    def from_bytes(self, data: bytes, formats: tuple[str, ...] | None = None) -> np.ndarray:
        """The texels of an image held in memory, of one of `formats` (Pillow's names)."""
        return self._texels(hashlib.sha256(data).digest(),
                            lambda: Image.open(io.BytesIO(data), formats=formats), formats)

    def _texels(self, digest: bytes, open_image, formats) -> np.ndarray:
        got = self._decoded.get(digest)
        if got is None:
            got = self._decoded[digest] = self._decode(open_image)
        elif formats is not None and got.format not in formats:
            raise ImageError(f"cannot decode the image (a {got.format}, not {' or '.join(formats)})")
        return got.texels

    def _decode(self, open_image) -> _Decoded:
        try:
            im = open_image()                 # (lazy: the header only, so far)
        except Exception as e:                # Pillow raises many types for bad data
            raise _undecodable(e) from None
        with im:
            w, h = im.size
            self.count(w, h)
            try:
                texels = linear_rgb(im)
            except MemoryError:
                raise ImageError(f"out of memory decoding its {w}x{h} pixels") from None
            except Exception as e:
                raise _undecodable(e) from None
            self.pixels += w * h
            return _Decoded(texels, im.format)

    def count(self, w: int, h: int) -> None:
        """ImageError unless a w x h image may be decoded and the scene hold it too."""
        n, most = w * h, limits.MAX_SCENE_IMAGE_PIXELS
        if n <= 0:
            raise ImageError("an image with no pixels")
        if n > limits.MAX_IMAGE_PIXELS:
            raise ImageError(f"{w}x{h} pixels, more than the limit of {limits.MAX_IMAGE_PIXELS} "
                             "for one image (e.g. 4096x4096)")
        if self.pixels + n > most:
            raise ImageError(f"{w}x{h} pixels would bring the scene's images to "
                             f"{self.pixels + n} pixels, more than the limit of {most} for a "
                             "scene (all its textures together, each distinct image once)")

    def tinted(self, texels: np.ndarray, rgb: np.ndarray) -> np.ndarray:
        """texels * rgb (float32), made once for each pair and counted as an image of its
        own; the texels themselves where rgb is white."""
        rgb = np.asarray(rgb, np.float32)
        if (rgb == 1.0).all():
            return texels
        key = (id(texels), rgb.tobytes())
        got = self._tinted.get(key)
        if got is None:
            self.count(texels.shape[1], texels.shape[0])
            gl_rows = np.multiply(texels[::-1], rgb)          # (GL row order, as decoded)
            got = self._tinted[key] = gl_rows[::-1]
            got.flags.writeable = False
            self.pixels += texels.shape[0] * texels.shape[1]
        return got

    def texture(self, texels: np.ndarray, path: Path | None = None) -> Texture:
        """The one image Texture drawing `texels` (its path: the first file named for it)."""
        got = self._textures.get(id(texels))
        if got is None:
            got = self._textures[id(texels)] = Texture(kind="image", path=path, image=texels)
        return got
