"""Compare and sweep as pandas DataFrames: one row per variant and region, with the columns
of `hmblur sweep`'s table (variant, mode, region, pixels, flip, psnr, ssim)."""
from __future__ import annotations

from os import PathLike
from pathlib import Path
from typing import Callable, Iterable

import pandas as pd

from world.scene import Scene
from viewer.eval.comparison import REALTIME, Comparison, Variant, check_variant
from viewer.eval.strip import REGION_ORDER
from viewer.io.sidecar import version
from viewer.render.modes.user import UserPass
from viewer.sweep.run import run_sweep
from viewer.sweep.spec import load_sweep
from .methods import as_method
from .renderer import Params, Renderer

__all__ = ["variants_of", "comparison_table", "compare", "sweep"]

TABLE_COLUMNS = ("variant", "mode", "region", "pixels", "flip", "psnr", "ssim")
VariantLike = str | tuple[str, str | UserPass | Callable] | Variant


def variants_of(items: Iterable[VariantLike]) -> list[Variant]:
    """Variants from a mode name ("mcguire"), a (name, user pass) pair (a UserPass, a
    `glsl:PATH` / `py:PATH:FUNCTION` text or a callable), a (name, "MODE") pair or a
    Variant; checked as --variant is, no name twice."""
    out: list[Variant] = []
    for item in items:
        if isinstance(item, Variant):
            v = item
        elif isinstance(item, str):
            v = Variant(item, item)
        else:
            name, what = item
            if isinstance(what, str) and what in REALTIME:
                v = Variant(name, what)
            else:
                m = as_method(what)
                v = Variant(name, m.kind, {}, m)
        check_variant(v, f"variant {v.name!r}")
        if any(u.name == v.name for u in out):
            raise ValueError(f"variant {v.name!r} is named twice")
        out.append(v)
    return out


def comparison_table(c: Comparison, variants: list[Variant]) -> pd.DataFrame:
    """The Comparison's scores as rows (variant, mode, region, pixels, flip, psnr, ssim),
    variants in order, regions as compare's tables order them."""
    rows = []
    for v in variants:
        table = c.table[v.name]
        for region in REGION_ORDER:
            if region in table:
                m = table[region]
                rows.append((v.name, v.mode, region, m["pixels"], m["flip"], m["psnr"],
                             m["ssim"]))
    df = pd.DataFrame(rows, columns=TABLE_COLUMNS)
    return df.astype({"pixels": "int64", "flip": "float64", "psnr": "float64",
                      "ssim": "float64"})


def compare(scene: Scene | str | PathLike, variants: Iterable[VariantLike] = REALTIME,
            time: float | None = None, params: Params = None, seed: int = 0,
            size: tuple[int, int] | None = None, renderer: Renderer | None = None
            ) -> pd.DataFrame:
    """`hmblur compare` as a table: the reference, then each variant scored per region
    (variants: see variants_of). `renderer`: one to reuse (else one is made and released)."""
    vs = variants_of(variants)
    own = renderer is None
    r = Renderer(size) if own else renderer
    try:
        c = r.compare_frame(scene, vs, time, params, seed, size=size)
    finally:
        if own:
            r.release()
    return comparison_table(c, vs)


def sweep(spec: str | PathLike, out: str | PathLike, workers: int = 0,
          scheduler: str | None = None, images: bool = False,
          timing: bool = False) -> pd.DataFrame:
    """`hmblur sweep SPEC --out OUT` (docs/sweeps.md): the cells not yet in OUT/cells run
    (workers 0: in this process; N: a local Dask cluster of N processes), the outputs
    written, and the table (OUT/table.parquet) returned."""
    out = Path(out)
    run_sweep(load_sweep(spec), out, version(), workers, scheduler, images, timing)
    return pd.read_parquet(out / "table.parquet")
