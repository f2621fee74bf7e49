"""Flicker: how much a sequence changes from frame to frame beyond what the reference
changes, per blur region.

Space: 8-bit sRGB codes (the written frames' values, 0..255), each channel alike. With
I_k the mode's frame k, R_k the reference's, and the temporal differences
dI_k = I_{k+1} - I_k and dR_k = R_{k+1} - R_k (signed, per pixel and channel):

    flicker(region) = mean over pairs k of [ mean over the pair's pixels p and channels c
                                             of |dI_k(p, c) - dR_k(p, c)| ]

A pair's pixels are those in the region in frame k or in frame k+1 (regions move with the
objects; taking both frames makes the figure the same played backwards). Pairs whose
region is empty are skipped; with no pair left the figure is None. A sequence that equals
the reference plus any constant error image has flicker 0: only error that changes over
time counts. `change` is the same mean of |dI_k| alone (and `reference_change` of |dR_k|),
the scale to read flicker against.
"""
from __future__ import annotations

import numpy as np

from viewer.render.modes.regions import NAMES
from .strip import REGION_ORDER


def _masks(region_a, region_b, shape) -> dict[str, np.ndarray]:
    out = {"all": np.ones(shape, dtype=bool)}
    if region_a is not None:
        for code, name in NAMES.items():
            out[name] = (np.asarray(region_a) == code) | (np.asarray(region_b) == code)
    return out


class FlickerAccumulator:
    """Feed one frame at a time: add(test, ref, region) with uint8 (H,W,3) sRGB images and
    an (H,W) region map (or None: only "all")."""

    def __init__(self):
        self._prev = None
        self._sums = {}       # region -> [sum of flicker, sum of change, sum of ref change, pairs]

    def add(self, test, ref, region=None):
        t = np.asarray(test, dtype=np.int16)
        r = np.asarray(ref, dtype=np.int16)
        if t.shape != r.shape or t.ndim != 3:
            raise ValueError(f"flicker: test {t.shape} and reference {r.shape} must be one (H,W,3) shape")
        if self._prev is not None:
            pt, pr, pregion = self._prev
            dt, dr = t - pt, r - pr
            err = np.abs(dt - dr).mean(axis=2)
            change, ref_change = np.abs(dt).mean(axis=2), np.abs(dr).mean(axis=2)
            for name, mask in _masks(pregion, region, t.shape[:2]).items():
                if mask.any():
                    s = self._sums.setdefault(name, [0.0, 0.0, 0.0, 0])
                    s[0] += float(err[mask].mean())
                    s[1] += float(change[mask].mean())
                    s[2] += float(ref_change[mask].mean())
                    s[3] += 1
        self._prev = (t, r, None if region is None else np.asarray(region))

    def result(self) -> dict[str, dict]:
        """{region: {"flicker", "change", "reference_change", "pairs"}} for every region
        (values None where no pair had pixels in it)."""
        regions = REGION_ORDER if (self._prev is not None and self._prev[2] is not None) else ("all",)
        out = {}
        for name in regions:
            s = self._sums.get(name)
            if s is None:
                out[name] = {"flicker": None, "change": None, "reference_change": None, "pairs": 0}
            else:
                n = s[3]
                out[name] = {"flicker": s[0] / n, "change": s[1] / n,
                             "reference_change": s[2] / n, "pairs": n}
        return out


def flicker(tests, refs, regions=None) -> dict[str, dict]:
    """The figures of whole sequences (lists of frames)."""
    acc = FlickerAccumulator()
    for k, (t, r) in enumerate(zip(tests, refs)):
        acc.add(t, r, None if regions is None else regions[k])
    return acc.result()
