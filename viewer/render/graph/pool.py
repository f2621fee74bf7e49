"""Named, size-dependent textures and their framebuffers.

The pool owns every render target. A pass asks for a texture by name with its spec; a
changed spec or frame size reallocates it (so a resize needs no bookkeeping elsewhere), and
framebuffers that used it are dropped. Nothing else holds a GL texture across frames.

While a pipeline runs a pass (`opened_to`), the pool checks each access against the pass's
declarations, as Frame.host does for host resources: a texture bound or read must be
one of its `inputs` or `produces`, a texture drawn into, cleared, written or allocated
one of its `produces` and none of its `inputs`, and a read-back to the host (`read_back`, the one way a pass reads
GPU data) one of its `reads_back`. Outside a pipeline (a pass run on its own, as unit
tests do, the sub-exposure accumulation, the caller reading results) nothing is checked.
"""
from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from viewer.render.graph import depth
from .framebuffers import park_framebuffer
from .opened import OpenToPass


@dataclass(frozen=True)
class TexSpec:
    components: int
    dtype: str                 # moderngl dtype: "f4", "f2", "u4", "u1"
    tile: int = 1              # 1 = full resolution; k = ceil(size / k) tiles
    filter: str = "nearest"    # or "linear"

    def size(self, full: tuple[int, int]) -> tuple[int, int]:
        return (-(-full[0] // self.tile), -(-full[1] // self.tile))


@dataclass(frozen=True)
class ReadBack:
    """A GPU-to-host read a pass makes: a pool texture by name, or (kept) a texture the
    renderer keeps across frames, labelled; `when` says when it happens where that is
    not every frame."""
    name: str
    when: str = ""
    kept: bool = False


class ResourcePool(OpenToPass):
    def __init__(self, ctx: moderngl.Context):
        super().__init__()
        self.ctx = ctx
        self.size = (1, 1)
        self._tex: dict[str, tuple[TexSpec, tuple[int, int], moderngl.Texture]] = {}
        self._fbo: dict[tuple, moderngl.Framebuffer] = {}
        self._depth: dict[tuple[int, int], moderngl.Texture] = {}
        # name -> (x0, y0, x1, y1): the GL pixel box written since the texture's last clear
        # (None: nothing). A texture without an entry may hold anything: clear it all.
        self._written: dict[str, tuple[int, int, int, int] | None] = {}
        # name -> (tile geometry, boolean tile map): the tiles a tiled pass wrote whole, the
        # texture zero elsewhere (mark_tiles); dropped by any other write.
        self._tiles: dict[str, tuple] = {}
        self.made: set[str] = set()        # allocated or written since begin()

    def _check(self, names, write: bool):
        p = self._pass
        if write and p is not None:
            sampled = [n for n in names if n in p.inputs]
            if sampled:
                raise RuntimeError(f"pass {p.name} writes texture {', '.join(sampled)}, which "
                                   "it declares as an input (a texture drawn into while it is "
                                   "sampled is undefined in GL)")
        if write:
            self._require(names, lambda p: p.produces, "writes texture {}", "produces")
        else:
            self._require(names, lambda p: (*p.inputs, *p.produces), "reads texture {}",
                          "inputs")

    def check_write(self, names):
        """Raise unless the open pass (if any) declares every one of `names` it writes."""
        self._check(names, write=True)
        self.made.update(names)

    def read_back(self, name: str, texture: moderngl.Texture | None = None,
                  viewport=None, components: int | None = None, dtype: str | None = None
                  ) -> bytes:
        """Texture `name` read to the host (inside `viewport`, x, y, w, h GL pixels, where
        given): the one GPU-to-host read of a pass, which must declare it in
        `reads_back`. `texture`: a kept texture (not the pool's), labelled `name`."""
        self._require((name,), lambda p: {r.name for r in p.reads_back},
                      "reads texture {} back to the host", "reads_back")
        if texture is not None:
            return texture.read()
        if viewport is None:
            return self.get(name).read()
        return self.framebuffer((name,), read=True).read(
            viewport=viewport, components=components or self.spec(name).components,
            dtype=dtype or self.spec(name).dtype)

    def begin(self):
        """A frame starts: `made` collects the textures it allocates or writes."""
        self.made = set()

    def resize(self, size: tuple[int, int]):
        self.size = (int(size[0]), int(size[1]))

    def texture(self, name: str, spec: TexSpec) -> moderngl.Texture:
        self._check((name,), write=True)
        self.made.add(name)
        size = spec.size(self.size)
        have = self._tex.get(name)
        if have and have[0] == spec and have[1] == size:
            return have[2]
        self.discard(name)
        tex = self.ctx.texture(size, spec.components, dtype=spec.dtype)
        f = moderngl.LINEAR if spec.filter == "linear" else moderngl.NEAREST
        tex.filter = (f, f)
        tex.repeat_x = tex.repeat_y = False
        self._tex[name] = (spec, size, tex)
        return tex

    def get(self, name: str) -> moderngl.Texture:
        """Texture `name`, to bind or read (a pass writes through framebuffer() or
        check_write() first)."""
        self._check((name,), write=False)
        return self._tex[name][2]

    def spec(self, name: str) -> TexSpec:
        return self._tex[name][0]

    def names(self) -> list[str]:
        return list(self._tex)

    def depth_buffer(self) -> moderngl.Texture:
        if self.size not in self._depth:
            park_framebuffer(self.ctx)
            for d in self._depth.values():
                d.release()
            self._depth = {self.size: depth.depth_texture(self.ctx, self.size)}
        return self._depth[self.size]

    def framebuffer(self, names: tuple[str, ...], depth: bool = False, read: bool = False
                    ) -> moderngl.Framebuffer:
        """The framebuffer of textures `names` (and the depth buffer), to draw into, or
        with `read` to copy or read from."""
        self._check(names, write=not read)
        if not read:
            self.made.update(names)
        key = (names, depth, self.size if depth else None)
        fbo = self._fbo.get(key)
        if fbo is None:
            fbo = self.ctx.framebuffer([self._tex[n][2] for n in names],
                                       self.depth_buffer() if depth else None)
            self._fbo[key] = fbo
        return fbo

    def mark_written(self, names, box: tuple[int, int, int, int] | None = None):
        """Record that `names` were written inside `box` (x0, y0, x1, y1, GL pixels); None
        means anywhere."""
        for n in names:
            self._tiles.pop(n, None)
            if box is None:
                self._written.pop(n, None)
            elif n in self._written:
                self._written[n] = union_of_two(self._written[n], box)

    def written_box(self, name: str):
        """The box written since `name`'s last clear: None if nothing, "unknown" if it
        may hold anything (never cleared, reallocated, written full screen)."""
        return self._written.get(name, "unknown")

    def clear(self, names: tuple[str, ...], value=(0.0, 0.0, 0.0, 0.0)):
        """Clear textures `names` (one framebuffer) to `value`, only inside the box written
        since their last clear: a memset of a few thousand pixels instead of megabytes
        where a pass writes little (the revealed layers, the ray mask)."""
        self._check(names, write=True)     # (also where nothing is left to clear)
        box = None
        for n in names:
            w, h = self._tex[n][1]
            box = union_of_two(box, self._written[n] if n in self._written else (0, 0, w, h))
        if box is not None:
            x0, y0, x1, y1 = box
            self.framebuffer(tuple(names)).clear(*value, viewport=(x0, y0, x1 - x0, y1 - y0))
        for n in names:
            self._written[n] = None
            self._tiles.pop(n, None)

    def stale_tiles(self, names: tuple[str, ...], tiles) -> np.ndarray | None:
        """Before a pass writes every texel of `tiles` (a TileList) in `names`: where a
        tiled pass of the same tile geometry wrote them last, the tiles it wrote that are
        not drawn again (a boolean tile map; all False when the tiles repeat, as under a
        still camera), the only texels outside `tiles` that are not 0; None where that is
        not known (clear() then)."""
        key, grid = _tile_map(tiles)
        marks = [self._tiles.get(n) for n in names]
        if not all(m is not None and m[0] == key for m in marks):
            return None
        stale = np.zeros_like(grid)
        for m in marks:
            stale |= m[1] & ~grid
        return stale

    def mark_tiles(self, names, tiles):
        """`names` hold nonzero texels only inside `tiles` (a TileList), every texel of
        which a pass has just written (after tile_runs.clear_outside)."""
        key, grid = _tile_map(tiles)
        for n in names:
            self._written[n] = tiles.box
            self._tiles[n] = (key, grid)

    def discard(self, name: str):
        """Release `name` if held, and forget what was written to it (a reallocation, or a
        buffer a pass writes only in some settings)."""
        if name in self._tex:
            self._drop(name)
        self._written.pop(name, None)
        self._tiles.pop(name, None)

    def _drop(self, name: str):
        park_framebuffer(self.ctx)
        for key in [k for k in self._fbo if name in k[0]]:
            self._fbo.pop(key).release()
        self._tex.pop(name)[2].release()

    def release(self):
        park_framebuffer(self.ctx)
        for fbo in self._fbo.values():
            fbo.release()
        for _, _, tex in self._tex.values():
            tex.release()
        for d in self._depth.values():
            d.release()
        self._fbo.clear(), self._tex.clear(), self._depth.clear(), self._written.clear()
        self._tiles.clear()


def _tile_map(tiles) -> tuple[tuple, np.ndarray]:
    """(tile geometry, boolean map (rows, columns) of the listed tiles) of a TileList."""
    tile, tile_h, (w, h) = tiles.tile, tiles.tile_h, tiles.size
    grid = np.zeros((-(-h // tile_h), -(-w // tile)), bool)
    if tiles.count:
        grid[tiles.tiles[:, 1], tiles.tiles[:, 0]] = True
    return (tile, tile_h, (w, h)), grid


def union_of_two(a, b):
    """The box around boxes a and b (x0, y0, x1, y1); None ones left out."""
    if a is None:
        return b
    if b is None:
        return a
    return (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))
