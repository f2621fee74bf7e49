"""sRGB encoding and atomic, deterministic file output.

Encoding (SCENE_FORMAT.md): linear colour is clamped to [0, 1] once, passed through the
standard sRGB transfer function in float64, and stored as `floor(255 * srgb + 0.5)`.
Non-finite input is mapped before the clamp: NaN -> 0, +inf -> 1, -inf -> 0, so a bad
pixel shows up black instead of poisoning the encoder (numpy would cast NaN to 0 anyway,
but only by accident and with a warning).

Writers go through a temporary file in the destination directory followed by
`os.replace`, so a reader never sees a half-written file and a failed write leaves the
previous file (or nothing) in place.
"""
from __future__ import annotations

import io
import json
import math
import os
import secrets
from pathlib import Path
from typing import Any, Callable

import numpy as np
from PIL import Image

_SRGB_LINEAR_MAX = 0.0031308   # linear-side breakpoint of the sRGB curve
_SRGB_ENCODED_MAX = 0.04045    # encoded-side breakpoint (decoding)


def _clamped(linear) -> np.ndarray:
    x = np.asarray(linear, dtype=np.float64)
    x = np.nan_to_num(x, nan=0.0, posinf=1.0, neginf=0.0)
    return np.clip(x, 0.0, 1.0)


def _encode(x: np.ndarray) -> np.ndarray:
    """sRGB transfer function on float64 values already in [0, 1]."""
    return np.where(x <= _SRGB_LINEAR_MAX, 12.92 * x,
                    1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def linear_to_srgb8(linear) -> np.ndarray:
    """Linear colour (any shape) -> uint8 sRGB: clamp once, encode, floor(255*s + 0.5)."""
    s = _encode(_clamped(linear))
    return np.floor(255.0 * s + 0.5).astype(np.uint8)


def srgb_float(linear) -> np.ndarray:
    """Linear colour -> float32 sRGB in [0, 1], unquantised (what FLIP's "LDR" expects)."""
    return _encode(_clamped(linear)).astype(np.float32)


def srgb8_to_linear(srgb8) -> np.ndarray:
    """uint8 sRGB -> float32 linear (inverse transfer function, computed in float64)."""
    c = np.asarray(srgb8, dtype=np.float64) / 255.0
    lin = np.where(c <= _SRGB_ENCODED_MAX, c / 12.92, np.power((c + 0.055) / 1.055, 2.4))
    return lin.astype(np.float32)


# --- atomic writers ------------------------------------------------------------------

def _atomic_write(path, write: Callable[[io.BufferedWriter], None]) -> Path:
    """Run `write(fileobj)` on a temp file beside `path`, fsync, then rename over it."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    # os.open with 0o666 lets the umask decide the final mode, as a plain open() would.
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def write_png_atomic(path, image) -> Path:
    """Write a uint8 (H,W,3) RGB or (H,W) grey image as PNG with no metadata chunks.

    Pillow writes no tIME/tEXt chunks unless asked, and the compression level is pinned,
    so the same pixels give the same bytes.
    """
    a = np.asarray(image)
    if a.dtype != np.uint8:
        raise ValueError(f"write_png_atomic: expected uint8 pixels, got {a.dtype}")
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] == 3)):
        raise ValueError(f"write_png_atomic: expected (H,W) or (H,W,3), got {a.shape}")
    img = Image.fromarray(np.ascontiguousarray(a), mode="L" if a.ndim == 2 else "RGB")
    return _atomic_write(path, lambda f: img.save(f, format="PNG", compress_level=6))


def json_safe(obj: Any) -> Any:
    """Plain-JSON form of `obj`: numpy scalars/arrays become Python values and lists,
    tuples become lists, and non-finite floats become the strings "inf", "-inf", "nan"
    (standard JSON has no infinities; PSNR of identical images is inf)."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, np.generic):
        return json_safe(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return "nan" if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
    return obj


def write_json_atomic(path, obj: Any) -> Path:
    """Write `obj` as JSON (sorted keys, indent 2, trailing newline) via `json_safe`."""
    text = json.dumps(json_safe(obj), sort_keys=True, indent=2, allow_nan=False) + "\n"
    data = text.encode("utf-8")  # encode first: a serialisation error must not touch disk
    return _atomic_write(path, lambda f: f.write(data))


def write_npy_atomic(path, array) -> Path:
    """Write one array in .npy format (no pickles), atomically."""
    a = np.asarray(array)
    return _atomic_write(path, lambda f: np.save(f, a, allow_pickle=False))
