"""Tile reductions of a velocity buffer (docs/algorithms.md 1.2, 1.3), shared by the blur modes.

TileMax keeps, per k x k tile, the velocity vector of largest magnitude; it runs as two
separable passes (k x 1 into a strip texture of ceil(W/k) x H, then 1 x k). NeighborMax
keeps the largest TileMax vector over the 3x3 tiles around each tile. Tiles are counted
from the GL origin (bottom-left); the last column and row of tiles may be partial.

Every pass is parameterised by its input and output texture names, so another mode can
run the same chain on its own velocity buffer under its own names. Given paths (the
hybrid's, glsl/passes/path.glsl), the chain ranks by path extent and carries the winner's path
in OUTPUT_path (and OUTPUT_path2) beside its chord.
"""
from __future__ import annotations

from dataclasses import dataclass

from .blur_common import max_radius_px
from viewer.render.graph.frame import Frame
from viewer.render.graph.passes import FullscreenPass, Pass
from viewer.render.graph.pool import TexSpec
from viewer.render.passes.gbuffer import path_names, path_samplers




@dataclass(frozen=True)
class StripSpec(TexSpec):
    """A texture tiled along x only: ceil(W / tile) x H (the TileMax k x 1 intermediate)."""

    def size(self, full: tuple[int, int]) -> tuple[int, int]:
        return (-(-full[0] // self.tile), full[1])


class TileMaxPass(FullscreenPass):
    """One separable TileMax step: axis "x" reduces k x 1 (full-size input -> strip),
    axis "y" reduces 1 x k (strip -> tiles)."""
    fragment = "passes/tilemax.frag"

    def __init__(self, source: str, output: str, axis: str, tile=max_radius_px, select=None,
                 segments: int = 1, paths: tuple[str, ...] = (), select_reads=()):
        """select(frame, k): a TileList over the output's texels that can be nonzero (the
        rest is cleared to 0, the value of a still strip), or None for all of them;
        select_reads: the host resources it reads (the pass's host_inputs).
        segments: the configuration's path segments; paths: the source's path
        targets (glsl/passes/path.glsl), read where segments > 1."""
        if axis not in ("x", "y"):
            raise ValueError(f"TileMaxPass axis must be 'x' or 'y', got {axis!r}")
        self.name = output
        self.path_outputs = path_names(output, 2 * len(paths))   # one per source path
        self.inputs, self.produces = (source, *paths), (output, *self.path_outputs)
        self.source, self.output, self.axis, self.tile = source, output, axis, tile
        self.select, self.segments, self.paths = select, segments, paths
        self.host_inputs = tuple(select_reads)

    def defines(self, frame: Frame):
        return {"SEGMENTS": self.segments}

    def outputs(self, frame: Frame):
        k = self.tile(frame)
        strip = self.axis == "x"
        spec = StripSpec(2, "f4", tile=k) if strip else TexSpec(2, "f4", tile=k)
        path = StripSpec(4, "f4", tile=k) if strip else TexSpec(4, "f4", tile=k)
        n = self.segments // 2
        return {self.output: spec, **{name: path for name in self.path_outputs[:n]}}

    def execute(self, frame: Frame):
        k = self.tile(frame)
        uniforms = {"u_tile": k, "u_axis": (1, 0) if self.axis == "x" else (0, 1)}
        tiles = self.select(frame, k) if self.select is not None else None
        if tiles is not None:
            uniforms["u_viewport"] = tuple(float(x) for x in tiles.size)
        n = self.segments // 2
        textures = {"u_velocity": self.source, **path_samplers(self.paths[:n])}
        self.draw(frame, (self.output, *self.path_outputs[:n]), textures, uniforms,
                  tiles=tiles)


class NeighborMaxPass(FullscreenPass):
    """The largest of the 3x3 tile vectors around each tile (centre wins ties);
    diagonal_toward: a diagonal neighbour only where its vector points toward the tile
    (Guertin et al. 2014)."""
    fragment = "passes/neighbormax.frag"

    def __init__(self, source: str, output: str, tile=max_radius_px, segments: int = 1,
                 paths: tuple[str, ...] = (), diagonal_toward: bool = False):
        self.name = output
        self.path_outputs = path_names(output, 2 * len(paths))   # one per source path
        self.inputs, self.produces = (source, *paths), (output, *self.path_outputs)
        self.source, self.output, self.tile = source, output, tile
        self.segments, self.paths = segments, paths
        self.diagonal_toward = diagonal_toward

    def defines(self, frame: Frame):
        return {"SEGMENTS": self.segments, "DIAGONAL_TOWARD": int(self.diagonal_toward)}

    def outputs(self, frame: Frame):
        k = self.tile(frame)
        n = self.segments // 2
        return {self.output: TexSpec(2, "f4", tile=k),
                **{name: TexSpec(4, "f4", tile=k) for name in self.path_outputs[:n]}}

    def execute(self, frame: Frame):
        n = self.segments // 2
        self.draw(frame, (self.output, *self.path_outputs[:n]),
                  {"u_tiles": self.source, **path_samplers(self.paths[:n])})


def tile_passes(source: str, prefix: str, tile=max_radius_px, select_x=None,
                segments: int = 1, paths: tuple[str, ...] = (),
                diagonal_toward: bool = False, select_reads=()) -> list[Pass]:
    """TileMax x, TileMax y and NeighborMax of `source`, producing PREFIX_tilemax_x,
    PREFIX_tilemax and PREFIX_neighbormax; select_x, select_reads: TileMaxPass's `select`
    for the first and the host resources it reads; paths: the source's path targets,
    carried along where segments > 1; diagonal_toward: NeighborMaxPass's."""
    tx, ty, nm = f"{prefix}_tilemax_x", f"{prefix}_tilemax", f"{prefix}_neighbormax"
    carried = 2 * len(paths)      # the path pieces the tile passes carry
    return [TileMaxPass(source, tx, "x", tile, select_x, segments, paths, select_reads),
            TileMaxPass(tx, ty, "y", tile, None, segments, path_names(tx, carried)),
            NeighborMaxPass(ty, nm, tile, segments, path_names(ty, carried), diagonal_toward)]
