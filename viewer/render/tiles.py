"""Tile reductions of a velocity buffer (ALGORITHMS.md 1.2, 1.3), shared by the blur modes.

TileMax keeps, per k x k tile, the velocity vector of largest magnitude; it runs as two
separable passes (k x 1 into a strip texture of ceil(W/k) x H, then 1 x k). NeighborMax
keeps the largest TileMax vector over the 3x3 tiles around each tile. Tiles are counted
from the GL origin (bottom-left); the last column and row of tiles may be partial.

Every pass is parameterised by its input and output texture names, so another mode can
run the same chain on its own velocity buffer under its own names.
"""
from __future__ import annotations

from dataclasses import dataclass

from .blur_common import max_radius_px
from .frame import Frame
from .passes import FullscreenPass, Pass
from .pool import TexSpec


@dataclass(frozen=True)
class StripSpec(TexSpec):
    """A texture tiled along x only: ceil(W / tile) x H (the TileMax k x 1 intermediate)."""

    def size(self, full: tuple[int, int]) -> tuple[int, int]:
        return (-(-full[0] // self.tile), full[1])


class TileMaxPass(FullscreenPass):
    """One separable TileMax step: axis "x" reduces k x 1 (full-size input -> strip),
    axis "y" reduces 1 x k (strip -> tiles)."""
    fragment = "tilemax.frag"

    def __init__(self, source: str, output: str, axis: str, tile=max_radius_px, select=None):
        """select(frame, k): a TileList over the output's texels that can be nonzero (the
        rest is cleared to 0, the value of a still strip), or None for all of them."""
        if axis not in ("x", "y"):
            raise ValueError(f"TileMaxPass axis must be 'x' or 'y', got {axis!r}")
        self.name = output
        self.inputs, self.produces = (source,), (output,)
        self.source, self.output, self.axis, self.tile = source, output, axis, tile
        self.select = select

    def outputs(self, frame: Frame):
        k = self.tile(frame)
        spec = StripSpec(2, "f4", tile=k) if self.axis == "x" else TexSpec(2, "f4", tile=k)
        return {self.output: spec}

    def execute(self, frame: Frame):
        k = self.tile(frame)
        uniforms = {"u_tile": k, "u_axis": (1, 0) if self.axis == "x" else (0, 1)}
        tiles = self.select(frame, k) if self.select is not None else None
        if tiles is not None:
            uniforms["u_viewport"] = tuple(float(x) for x in tiles.size)
        self.draw(frame, (self.output,), {"u_velocity": self.source}, uniforms, tiles=tiles)


class NeighborMaxPass(FullscreenPass):
    """The largest of the 3x3 tile vectors around each tile (centre wins ties);
    diagonal_toward: a diagonal neighbour only where its vector points toward the tile
    (Guertin et al. 2014)."""
    fragment = "neighbormax.frag"

    def __init__(self, source: str, output: str, tile=max_radius_px,
                 diagonal_toward: bool = False):
        self.name = output
        self.inputs, self.produces = (source,), (output,)
        self.source, self.output, self.tile = source, output, tile
        self.diagonal_toward = diagonal_toward

    def defines(self, frame: Frame):
        return {"DIAGONAL_TOWARD": int(self.diagonal_toward)}

    def outputs(self, frame: Frame):
        return {self.output: TexSpec(2, "f4", tile=self.tile(frame))}

    def execute(self, frame: Frame):
        self.draw(frame, (self.output,), {"u_tiles": self.source})


def tile_passes(source: str, prefix: str, tile=max_radius_px, select_x=None,
                diagonal_toward: bool = False) -> list[Pass]:
    """TileMax x, TileMax y and NeighborMax of `source`, producing PREFIX_tilemax_x,
    PREFIX_tilemax and PREFIX_neighbormax; select_x: TileMaxPass's `select` for the first;
    diagonal_toward: NeighborMaxPass's."""
    return [TileMaxPass(source, f"{prefix}_tilemax_x", "x", tile, select_x),
            TileMaxPass(f"{prefix}_tilemax_x", f"{prefix}_tilemax", "y", tile),
            NeighborMaxPass(f"{prefix}_tilemax", f"{prefix}_neighbormax", tile, diagonal_toward)]
