"""Image quality of a test frame against the reference, per blur region (docs/algorithms.md 5.3).

Space: every metric is computed on sRGB values in [0, 1]. By default (quantize=True)
these are the 8-bit codes the PNG files hold, divided by 255, so the numbers can be
recomputed from the written images; quantize=False uses the unquantised sRGB float.
uint8 inputs are taken as already-encoded sRGB.

* PSNR: 10 log10(1 / MSE), MSE over every channel of the region's pixels (peak 1.0, the
  same as 20 log10(255) on 8-bit codes). Identical images give float("inf"), which
  imageio.write_json_atomic writes as the string "inf".
* SSIM: scikit-image's map (7x7 uniform window, data_range=1, channels averaged), meaned
  over the region's pixels that are at least 3 px from the image border: skimage drops
  that border from its own scalar, so "all" equals structural_similarity()'s value.
* FLIP: flip_evaluator.evaluate(ref, test, "LDR") error map (default 67 pixels per
  degree), meaned over the region.

An empty region (or, for SSIM, one lying wholly in the border) gives None.
"""
from __future__ import annotations

import flip_evaluator
import numpy as np
from skimage.metrics import structural_similarity

from viewer.io.imageio import linear_to_srgb8, srgb_float
from viewer.render.modes.regions import NAMES

SSIM_WIN = 7
SSIM_PAD = (SSIM_WIN - 1) // 2
METRICS = ("psnr", "ssim", "flip")
# The space of image_metrics' numbers (quantize=True), as `hmblur compare` states it beside
# them (docs/algorithms.md 5.3: each metric with its space).
SPACE = ("sRGB, the written PNGs' 8-bit codes / 255; PSNR peak 1.0 over every channel; "
         "SSIM scikit-image, 7x7 uniform window, data_range 1, channels averaged, pixels "
         "3 px or more from the border; FLIP flip-evaluator LDR, 67 pixels per degree")


def to_srgb(image, quantize: bool = True) -> np.ndarray:
    """Image -> float64 (H,W,3) sRGB in [0,1]: uint8 as codes, float as linear colour.

    float64 so that code/255 is as exact as it gets for PSNR and SSIM; FLIP gets float32."""
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"expected an (H,W,3) image, got shape {a.shape}")
    if a.dtype == np.uint8:
        return a / 255.0
    if quantize:
        return linear_to_srgb8(a) / 255.0
    return srgb_float(a).astype(np.float64)


def flip_map(ref_srgb: np.ndarray, test_srgb: np.ndarray) -> np.ndarray:
    """Per-pixel FLIP error (H,W) of float sRGB images."""
    # evaluate returns (error map, mean, parameters); applyMagma=False keeps the raw
    # (H,W,1) error instead of a colour-mapped picture of it
    err, _, _ = flip_evaluator.evaluate(np.ascontiguousarray(ref_srgb, np.float32),
                                        np.ascontiguousarray(test_srgb, np.float32),
                                        "LDR", applyMagma=False)
    return np.asarray(err, dtype=np.float64)[..., 0]


def metric_maps(test, ref, quantize: bool = True) -> dict[str, np.ndarray]:
    """Per-pixel maps (H,W) float64: squared error (channel mean), SSIM, FLIP."""
    t, r = to_srgb(test, quantize), to_srgb(ref, quantize)
    if t.shape != r.shape:
        raise ValueError(f"test {t.shape} and reference {r.shape} differ in shape")
    diff = t - r
    if min(t.shape[:2]) < SSIM_WIN:     # no window fits: no pixel has an SSIM (None)
        ssim = np.full(t.shape, np.nan)
    else:
        _, ssim = structural_similarity(r, t, win_size=SSIM_WIN, channel_axis=2,
                                        data_range=1.0, full=True)
    return {"sq_err": np.mean(diff * diff, axis=2),
            "ssim": np.mean(ssim, axis=2),
            "flip": flip_map(r, t)}


def _psnr(mse: float) -> float:
    return float("inf") if mse == 0.0 else float(10.0 * np.log10(1.0 / mse))


def _summary(maps: dict[str, np.ndarray], mask: np.ndarray, interior: np.ndarray) -> dict:
    n = int(np.count_nonzero(mask))
    inner = mask & interior
    return {
        "pixels": n,
        "psnr": _psnr(float(maps["sq_err"][mask].mean())) if n else None,
        "ssim": float(maps["ssim"][inner].mean()) if inner.any() else None,
        "flip": float(maps["flip"][mask].mean()) if n else None,
    }


def image_metrics(test, ref, region=None, quantize: bool = True) -> dict[str, dict]:
    """{"all": {...}} plus "static"/"inner"/"outer" when a region map is given; each
    entry holds pixels, psnr (dB), ssim and flip (see the module docstring)."""
    return region_metrics(metric_maps(test, ref, quantize), region)


def region_metrics(maps: dict[str, np.ndarray], region=None) -> dict[str, dict]:
    """image_metrics from maps made by metric_maps (so that a caller that also shows the
    FLIP map computes it once)."""
    h, w = maps["ssim"].shape
    interior = np.zeros((h, w), dtype=bool)
    interior[SSIM_PAD:h - SSIM_PAD, SSIM_PAD:w - SSIM_PAD] = True
    out = {"all": _summary(maps, np.ones((h, w), dtype=bool), interior)}
    if region is not None:
        region = np.asarray(region)
        if region.shape != (h, w):
            raise ValueError(f"region map {region.shape} does not match image {(h, w)}")
        for code, name in NAMES.items():
            out[name] = _summary(maps, region == code, interior)
    return out
