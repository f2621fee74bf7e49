"""The static objects' raster, kept across frames under a still camera (GBufferPass's
cache; docs/architecture.md).

Where the camera holds still over the exposure (its pose at the frame time, the shutter's
open and close and the path's times the same bits), the objects that never move draw the
same pixels at every time: colour, depths, normal, id, a zero displacement and zero path
offsets. The G-buffer pass then draws them once, after the background, into kept textures
(its layout's targets, the depth buffer, each pixel's static draw rank), and per frame
copies them into its targets (one blit, depth included) and draws only the movers.

The result is the full draw's to the bit, ties included. The full draw keeps at each
pixel the nearest fragment and, among equally near ones, the first drawn (objects front to
back by box centre, a strict depth test). So the raster is blitted in with each static's
depth one float farther (`far`): a mover drawn over it wins where it is as near as the
static or nearer, as a mover drawn before that static does; and before each mover the
statics that come before it in the order take their exact depth back (a depth-only pass,
glsl/passes/gbuffer_depth.frag, inside the movers' screen box), so that it loses its ties with
them.
Where every static comes before every mover, the exact depths are blitted; where every
mover comes first (wheel, living_room, thin), the blit is all.

Kept by everything the static pixels depend on (the camera's pose and lens, the size,
the shader variant: layout, path segments, lights; the background and the static objects
with their matrices; the scene by its GpuScene), never by the frame's time: a sub-frame
at another time finds it correct. Made the second time a key is asked for (a single
frame, or a camera the viewer is moving, draws as before, at no extra cost), at once for
a static-only pass (the hybrid's static layer, which is this raster). Only under reversed
Z: a float depth buffer, which the copies and `far` hold exactly (viewer/render/graph/depth.py).
"""
from __future__ import annotations

import functools
from collections import OrderedDict

import moderngl
import numpy as np

from world.transforms import box_corners

from viewer.render.graph import depth
from viewer.render.graph.framebuffers import park_framebuffer
from viewer.render.graph.gpu_scene import set_uniform
from viewer.render.graph.kept import KeptSlot
from viewer.render.graph.pool import TexSpec, union_of_two

# Kept rasters' memory at most (all layouts together): the least recently used goes
# first; a raster larger than this alone is not kept (~5 Mpx in the full layout).
BUDGET_BYTES = 256 << 20
# Keys asked for once, remembered to be made when asked again.
SEEN_KEYS = 8
# Pixels added around the movers' projected boxes (the shaders' float32 against float64).
BOX_MARGIN = 2
_BYTES = {"f4": 4, "f2": 2, "u4": 4, "u1": 1}


def still_key(frame, t: float, times, defines: dict) -> tuple | None:
    """(variant, view): the size and shader variant, and what the static objects' pixels
    show; None where they may change within the exposure (the camera's pose at one of
    `times` not that at t), where nothing is static, or without reversed Z."""
    cam = frame.camera
    pose = b"".join(a.tobytes() for a in cam.spec.pose(t))
    if any(b"".join(a.tobytes() for a in cam.spec.pose(tk)) != pose for tk in times):
        return None
    statics = tuple((o.id, o.matrix(t).tobytes()) for o in frame.scene.objects
                    if not o.moving)
    if not statics or not depth.reversed_z(frame.ctx):
        return None
    s = cam.spec
    view = (pose, float(s.fov_y), float(s.near), float(s.far), cam.width, cam.height,
            tuple(frame.scene.background), statics)
    return (frame.size, tuple(sorted(defines.items()))), view


def nbytes(size, specs: list[TexSpec]) -> int:
    """A raster's memory: its targets, the rank and two depth buffers."""
    per_pixel = sum(s.components * _BYTES[s.dtype] for s in specs) + 3 * 4
    return per_pixel * size[0] * size[1]


class StaticRaster:
    """The kept textures of one variant: `targets` (in attachment order), the rank target
    (R32UI: 1 + the static's place in the draw order, 0 background), the depth buffer and
    `far` (each depth one float farther), their framebuffers, and each rank's GL pixel box
    (boxes[r] = x0, y0, x1, y1; (w, h, 0, 0) where r is not seen). `key`: the view drawn;
    `far` and the boxes are made when first asked for (prepare)."""

    def __init__(self, ctx: moderngl.Context, gpu, size, specs: list[TexSpec]):
        self.ctx, self.gpu, self.size, self.specs = ctx, gpu, size, specs
        self.key = None
        self.targets = [_texture(ctx, size, s.components, s.dtype) for s in specs]
        self.rank = _texture(ctx, size, 1, "u4")
        self.depth = depth.depth_texture(ctx, size)
        self.depth.compare_func = ""           # sampled as values by gbuffer_depth.frag
        self.far = depth.depth_texture(ctx, size)
        self.draw_fbo = ctx.framebuffer(self.targets + [self.rank], self.depth)
        self.exact_fbo = ctx.framebuffer(self.targets, self.depth)   # blit sources
        self.far_fbo = ctx.framebuffer(self.targets, self.far)
        self.boxes = None

    @property
    def nbytes(self) -> int:
        return nbytes(self.size, self.specs)

    def drawn(self, key):
        """The raster now holds view `key` (its far depths and boxes not yet made)."""
        self.key, self.boxes = key, None

    def prepare(self, pool, ranks: int):
        """`far` from the depths, each rank's box from the rank target (read back once
        a view; a static-only pass, the hybrid's static layer, never asks)."""
        if self.boxes is not None:
            return
        w, h = self.size
        d = np.frombuffer(pool.read_back("static_raster", texture=self.depth), np.float32)
        self.far.write(np.nextafter(d, np.float32(0)).tobytes())    # (the clear 0 stays)
        r = np.frombuffer(pool.read_back("static_raster", texture=self.rank),
                          np.uint32).reshape(h, w)
        boxes = np.zeros((ranks + 1, 4), np.int64)
        for lo, hi, at, n in ((0, 2, np.arange(w)[None, :], w),
                              (1, 3, np.arange(h)[:, None], h)):
            seen = np.zeros((ranks + 1, n), bool)      # rank present in column / row
            seen[r, at] = True
            has = seen.any(1)
            boxes[:, lo] = np.where(has, seen.argmax(1), n)
            boxes[:, hi] = np.where(has, n - seen[:, ::-1].argmax(1), 0)
        self.boxes = boxes

    def box(self, first: int, end: int, within) -> tuple[int, int, int, int] | None:
        """The pixel box of ranks [first, end) inside box `within`; None if empty."""
        b = self.boxes[first:end]
        if not len(b):
            return None
        x0, y0 = max(b[:, 0].min(), within[0]), max(b[:, 1].min(), within[1])
        x1, y1 = min(b[:, 2].max(), within[2]), min(b[:, 3].max(), within[3])
        return (int(x0), int(y0), int(x1), int(y1)) if x0 < x1 and y0 < y1 else None

    def restore_depth(self, frame, fbo: moderngl.Framebuffer, first: int, end: int, box):
        """Write ranks [first, end)'s own depths into `fbo` (depth only) inside `box`
        through the depth test as the caller set it (glsl/passes/gbuffer_depth.frag)."""
        prog = frame.programs.get("graph/fullscreen.vert", "passes/gbuffer_depth.frag")
        self.rank.use(0)
        self.depth.use(1)
        set_uniform(prog, "u_rank", 0)
        set_uniform(prog, "u_depth", 1)
        set_uniform(prog, "u_ranks", (first, end))
        fbo.use()
        fbo.scissor = (box[0], box[1], box[2] - box[0], box[3] - box[1])
        frame.programs.empty_vao(prog).render(moderngl.TRIANGLES, vertices=3)
        fbo.scissor = None

    def release(self):
        park_framebuffer(self.ctx)
        for f in (self.draw_fbo, self.exact_fbo, self.far_fbo):
            f.release()
        for t in (*self.targets, self.rank, self.depth, self.far):
            t.release()


def _texture(ctx, size, components, dtype) -> moderngl.Texture:
    tex = ctx.texture(size, components, dtype=dtype)
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    return tex


class StaticRasters:
    """The kept rasters, one per variant (least recently used first; a variant's raster
    is drawn again for a new view, as when the viewer's camera stops elsewhere), the
    keys seen once, the objects' mesh boxes."""

    def __init__(self):
        self.rasters: OrderedDict[tuple, StaticRaster] = OrderedDict()
        self.seen: OrderedDict[tuple, None] = OrderedDict()
        self._corners: dict[int, np.ndarray | None] = {}

    def find(self, frame, key) -> StaticRaster | None:
        """The raster holding view `key`, or None."""
        for k in [k for k, r in self.rasters.items() if r.size != frame.size]:
            self.rasters.pop(k).release()       # (another size's: not asked for again)
        r = self.rasters.get(key[0])
        if r is None or r.key != key or r.gpu is not frame.gpu:
            return None
        self.rasters.move_to_end(key[0])
        return r

    def wanted(self, key, now: bool) -> bool:
        """Whether to draw key's raster: asked for the second time, or `now`."""
        if now or key in self.seen:
            self.seen.pop(key, None)
            return True
        self.seen[key] = None
        while len(self.seen) > SEEN_KEYS:
            self.seen.popitem(last=False)
        return False

    def make(self, frame, key, specs: list[TexSpec]) -> StaticRaster | None:
        """The raster to draw `key` into: its variant's (drawn again), or a new one made
        room for within the budget; None where it alone would not fit."""
        variant = key[0]
        r = self.rasters.get(variant)
        if r is not None and r.gpu is not frame.gpu:
            self.rasters.pop(variant).release()
            r = None
        if r is None:
            need = nbytes(frame.size, specs)
            if need > BUDGET_BYTES:
                return None
            while self.rasters and need + sum(x.nbytes for x in self.rasters.values()) \
                    > BUDGET_BYTES:
                self.rasters.popitem(last=False)[1].release()
            r = self.rasters[variant] = StaticRaster(frame.ctx, frame.gpu, frame.size, specs)
        self.rasters.move_to_end(variant)
        return r

    def movers_boxes(self, frame, movers, t: float) -> list:
        """Per mover, a GL pixel box (x0, y0, x1, y1) holding every fragment it draws at
        t (its mesh box's corners projected, a margin around), the whole image where a
        corner is not in front of the eye, None where it cannot reach the image."""
        w, h = frame.size
        vp = frame.camera.view_projection(t)
        boxes = []
        for o in movers:
            corners = self.corners(o, t)
            clip = None if corners is None else corners @ (vp @ o.matrix(t)).T
            if clip is None:
                boxes.append(None)
            elif not (clip[:, 3] > 0).all():
                boxes.append((0, 0, w, h))
            else:
                win = (clip[:, :2] / clip[:, 3:] * 0.5 + 0.5) * (w, h)
                lo = np.clip(np.floor(win.min(0)) - BOX_MARGIN, 0, (w, h)).astype(int)
                hi = np.clip(np.ceil(win.max(0)) + BOX_MARGIN, 0, (w, h)).astype(int)
                boxes.append((*lo, *hi) if (lo < hi).all() else None)
        return boxes

    def corners(self, obj, t: float) -> np.ndarray | None:
        """The 8 corners (homogeneous rows) of the object's mesh box (a skinned mesh's
        at t); None if it has no vertices."""
        if obj.skin is not None:
            return np.c_[box_corners(obj.vertices_at(t)), np.ones(8)]
        if obj.id not in self._corners:
            v = obj.mesh.vertices
            c = None
            if len(v):
                c = np.c_[box_corners(v), np.ones(8)]
            self._corners[obj.id] = c
        return self._corners[obj.id]

    def release(self):
        for r in self.rasters.values():
            r.release()
        self.rasters.clear()
        self.seen.clear()


KEPT_STATIC = KeptSlot("static_raster", StaticRasters,
                       "the static objects' raster under a still camera, by view")


def rasters(frame) -> StaticRasters:
    return frame.kept.get_or_make(KEPT_STATIC, StaticRasters)


def union(boxes):
    """The box around `boxes` (None ones left out); None if there is none."""
    box = functools.reduce(union_of_two, boxes, None)
    return None if box is None else tuple(int(x) for x in box)


def draw_plan(order) -> list:
    """The draw order as runs: a mover, or [first, end) of the static ranks in a row (a
    static's rank: 1 + its place among the statics)."""
    plan, rank = [], 0
    for o in order:
        if o.moving:
            plan.append(o)
            continue
        rank += 1
        if plan and isinstance(plan[-1], list):
            plan[-1][1] = rank + 1
        else:
            plan.append([rank, rank + 1])
    return plan
