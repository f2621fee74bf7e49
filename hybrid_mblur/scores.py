"""Scores of any image against a reference, per blur region: PSNR, SSIM and FLIP, computed
as `hmblur compare` computes them (viewer/eval/metrics.py: sRGB 8-bit codes / 255)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from viewer.eval.metrics import SPACE, image_metrics
from viewer.eval.strip import REGION_ORDER
from .results import Reference, Render

__all__ = ["scores", "SPACE", "COLUMNS"]

COLUMNS = ("pixels", "psnr", "ssim", "flip")


def _image(x) -> np.ndarray:
    return x.image if isinstance(x, Render) else np.asarray(x)


def scores(image: Render | np.ndarray, reference: Reference | np.ndarray,
           regions: np.ndarray | None = None) -> pd.DataFrame:
    """A DataFrame indexed by region ("all", then "static", "inner", "outer" where regions
    are known: `regions`, else the Reference's), columns pixels, psnr (dB), ssim, flip.
    Images: a Render, linear float (H, W, 3), or uint8 sRGB codes. An empty region's
    scores are NaN."""
    if regions is None and isinstance(reference, Reference):
        regions = reference.regions
    table = image_metrics(_image(image), _image(reference), regions)
    rows = [(region, *(table[region][c] for c in COLUMNS))
            for region in REGION_ORDER if region in table]
    df = pd.DataFrame(rows, columns=("region", *COLUMNS)).set_index("region")
    return df.astype({"pixels": "int64", "psnr": "float64", "ssim": "float64",
                      "flip": "float64"})
