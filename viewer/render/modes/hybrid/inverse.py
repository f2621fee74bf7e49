"""Inverse motion: what passes over a pixel at each time of the exposure, along every
point's true curve, in one frame (docs/algorithms.md 6.1).

For a rigid object O (world matrix M(t)) seen by a camera with view V(t), the point of O
that covers pixel p at time t_k lies on p's ray at t_k; mapped to the frame time it is
seen at q = proj(A_k X), A_k = V(t) M(t) M(t_k)^-1 V(t_k)^-1, X the ray's point at O's
depth. The composite (glsl/modes/hybrid/hybrid_inverse.frag) reads the G-buffer at q and
accepts O there when the surface it holds maps back onto p (A_k^-1), so a turning body's
streaks follow arcs. This host pass makes what the shader reads:

  hybrid_motion_table: per object id (a row; row 0 the background), per time of the
      exposure t_k = t_open + (k + 1/2) (t_close - t_open) / K (k < K = hybrid.curve_samples,
      the centres of K equal parts; a pixel's time samples are stratified over them),
      three affine maps, each as its top three rows (a texel a row): L_k = (V(t_k)
      M(t_k))^-1, view space at t_k to the object's own; F_k = V(t) M(t) L_k, view space
      at t_k to view space at the frame time (where the G-buffer holds the point);
      B_k = F_k^-1; and the object's screen box at t_k (a pixel outside it is not covered
      then). Then, once per object: its local bounding box (lo, hi: a ray that misses it
      at t_k is no candidate, and where it enters is the first depth guess), its kind:
      0 still (every static object shares the camera's map, its boxes unbounded), 1 rigid
      mover, 2 skinned mover (no rigid map: the shader walks its displacement instead),
      and its screen box over the exposure (a pixel outside it never looks for it);
  hybrid_candidates: per FINE tile, up to MAX_CANDIDATES movers whose screen bounds over
      the exposure reach it, nearest first (0: none);
  host inverse_tiles: the tiles where the composite follows motion exactly: in a frame
      where some mover's (or the camera's) screen paths bend more than motion.curve_px,
      every tile a mover reaches (every tile where the camera's own motion bends); the
      others, and every tile of a frame whose motion is straight, keep the linear
      composite.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from world.conventions import to_image
from world.errors import UserError
from world.path_bend import object_bends, object_points
from world.pose_table import PoseTable
from viewer.render.graph.frame import Frame
from viewer.render.graph.host import HostResource
from viewer.render.graph.passes import Pass
from viewer.render.graph.pool import TexSpec
from viewer.render.passes.tile_runs import FINE
from .tile_select import TILE_LISTS

MOTION_TABLE = "hybrid_motion_table"
CANDIDATES = "hybrid_candidates"
INVERSE_TILES = HostResource("inverse_tiles", np.ndarray,
                             "FINE tiles (GL rows) where the composite follows curves")
MAX_CANDIDATES = 4
# Texels per time: L_k, F_k, B_k (three rows each), the screen box; per object after the
# times': lo, hi, kind, the screen box over the exposure (the shaders get these offsets).
AT_L, AT_F, AT_B, AT_BOX, COLS = 0, 3, 6, 9, 10
AT_LO, AT_HI, AT_KIND, AT_REACH, TAIL = 0, 1, 2, 3, 4
UNBOUNDED = 3.0e38
KIND_STILL, KIND_RIGID, KIND_SKINNED = 0, 1, 2


@dataclass(frozen=True)
class TableSpec(TexSpec):
    """A texture of a fixed size, whatever the frame's."""
    width: int = 1
    height: int = 1

    def size(self, full: tuple[int, int]) -> tuple[int, int]:
        return (self.width, self.height)


def table_times(t_open: float, t_close: float, parts: int) -> np.ndarray:
    """t_k = t_open + (k + 1/2) (t_close - t_open) / K, k < K: the centres of K parts."""
    return t_open + (t_close - t_open) * (np.arange(parts) + 0.5) / parts


def object_row(view_t: np.ndarray, views: np.ndarray, model_t: np.ndarray,
               models: np.ndarray, lo, hi, kind: int, boxes: np.ndarray) -> np.ndarray:
    """One object's table row: K * COLS + TAIL texels (module doc), float64; `boxes` its
    screen box at each time (K, 4)."""
    local = np.linalg.inv(views @ models)                     # L_k = (V(t_k) M(t_k))^-1
    forward = (view_t @ model_t) @ local                      # F_k
    times = np.zeros((len(views), COLS, 4))
    times[:, AT_L:AT_L + 3] = local[:, :3]
    times[:, AT_F:AT_F + 3] = forward[:, :3]
    times[:, AT_B:AT_B + 3] = np.linalg.inv(forward)[:, :3]
    times[:, AT_BOX] = boxes
    tail = np.zeros((TAIL, 4))
    tail[AT_LO, :3], tail[AT_HI, :3], tail[AT_KIND, 0] = lo, hi, kind
    tail[AT_REACH] = (*boxes[:, :2].min(axis=0), *boxes[:, 2:].max(axis=0))
    return np.concatenate([times.reshape(-1, 4), tail])


def lookup_uniforms(frame: Frame) -> dict:
    """What glsl/modes/hybrid/inverse_common.glsl reads besides its textures."""
    p = frame.params["hybrid"]
    cam = frame.camera
    proj = cam.projection()
    return {"u_focal": (float(proj[0, 0]), float(proj[1, 1])),
            "u_viewport": tuple(float(x) for x in frame.size),
            "u_near": float(cam.spec.near),
            "u_parts": int(frame.params["hybrid"].curve_samples),
            "u_tolerance": float(p.tolerance), "u_depth_tolerance": float(p.depth_tolerance)}


def curved_tiles(frame: Frame) -> np.ndarray | None:
    """INVERSE_TILES, where the frame has tile lists of the same shape and some tile
    follows curves; else None (the linear passes everywhere). For the passes that declare
    both host inputs (the ray mask, the composite)."""
    tiles = frame.host.get(INVERSE_TILES)
    lists = frame.host.get(TILE_LISTS)
    if tiles is None or lists is None or tiles.shape != lists.shape or not tiles.any():
        return None
    return tiles


LOOKUP_DEFINES = {"TABLE_COLS": COLS, "AT_L": AT_L, "AT_F": AT_F, "AT_B": AT_B,
                  "AT_BOX": AT_BOX, "AT_LO": AT_LO, "AT_HI": AT_HI, "AT_KIND": AT_KIND,
                  "AT_REACH": AT_REACH, "KIND_STILL": KIND_STILL, "KIND_RIGID": KIND_RIGID,
                  "KIND_SKINNED": KIND_SKINNED}
# Times of the exposure at which the ray mask asks whether a pixel's own mover still
# covers it (evenly spaced): where one does not, the pixel is traced.
MASK_CHECKS = 8


class MotionTable(Pass):
    """Host: the motion table, the tiles' candidate movers and the tiles that bend
    (module doc), where the frame's motion bends; nothing drawn elsewhere."""
    name = "motion_table"
    runs_on = "cpu"
    produces = (MOTION_TABLE, CANDIDATES)
    host_outputs = (INVERSE_TILES,)

    def outputs(self, frame: Frame):
        k = int(frame.params["hybrid"].curve_samples)
        rows = len(frame.scene.objects) + 1
        most = int(frame.ctx.info.get("GL_MAX_TEXTURE_SIZE") or 1024)
        if rows > most:
            raise UserError(f"hybrid.curve = inverse: the scene's {rows - 1} objects need a "
                            f"motion table of {rows} rows, more than this GL driver's "
                            f"{most}: use hybrid.curve = steps")
        return {MOTION_TABLE: TableSpec(4, "f4", width=k * COLS + TAIL, height=rows),
                CANDIDATES: TexSpec(4, "u4", tile=FINE)}

    def execute(self, frame: Frame):
        scene, cam = frame.scene, frame.camera
        w, h = frame.size
        shape = (-(-h // FINE), -(-w // FINE))
        t = frame.time
        t_open, t_close = frame.exposure
        camera_moves = scene.camera.moving
        movers = [o for o in scene.objects if o.moving]
        # The movers' paths and, under a moving camera, the still objects' (the camera's
        # own motion), measured together.
        stills = [o for o in scene.objects if not o.moving] if camera_moves else []
        bends = (object_bends(scene, cam, t, frame.shutter, movers + stills)
                 > float(frame.params["motion"].curve_px))
        camera_bends = bool(bends[len(movers):].any())
        inverse = np.zeros(shape, bool)
        if frame.shutter <= 0.0 or not bends.any():
            frame.host.put(INVERSE_TILES, inverse)
            frame.stats["inverse_tiles"] = 0
            return
        k = int(frame.params["hybrid"].curve_samples)
        times = table_times(t_open, t_close, k)
        view_t = cam.view(t)
        views = (np.stack([cam.view(float(tk)) for tk in times]) if camera_moves
                 else np.broadcast_to(view_t, (k, 4, 4)))
        poses = PoseTable((*times, t))
        eye = np.eye(4)
        unbounded = np.tile([-UNBOUNDED, -UNBOUNDED, UNBOUNDED, UNBOUNDED], (k, 1))
        still = object_row(view_t, views, eye, np.broadcast_to(eye, views.shape),
                           np.full(3, -UNBOUNDED), np.full(3, UNBOUNDED), KIND_STILL,
                           unbounded)
        table = np.repeat(still[None], len(scene.objects) + 1, axis=0)
        candidates = np.zeros(shape + (MAX_CANDIDATES,), np.uint32)
        count = np.zeros(shape, np.int64)
        order = []
        for o in movers:
            models = poses.world(o)
            boxes, near = self._reach(frame, o, times, views, models[:k])
            order.append((near, o.id, o, boxes, models))
        dropped = 0
        for _, _, o, boxes, models in sorted(order, key=lambda x: (x[0], x[1])):
            table[o.id, k * COLS + AT_KIND, 0] = KIND_SKINNED
            if o.skin is None:
                lo, hi = frame.gpu.bounds[o.id]
                try:
                    table[o.id] = object_row(view_t, views, models[k], models[:k], lo, hi,
                                             KIND_RIGID, boxes)
                except np.linalg.LinAlgError:     # (scaled to nothing at some time: walked)
                    pass
            sel = self._tiles(self._union(boxes), shape, w, h)
            room = sel & (count < MAX_CANDIDATES)
            dropped += int((sel & ~room).sum())
            candidates[room, count[room]] = o.id
            count[room] += 1
            inverse |= sel
        if camera_bends:
            inverse[:] = True
        # Both in GL rows (a row per object id; tiles from the bottom): Frame.write takes
        # image rows.
        frame.write(MOTION_TABLE, to_image(table))
        frame.write(CANDIDATES, to_image(candidates))
        frame.host.put(INVERSE_TILES, inverse)
        frame.stats["inverse_tiles"] = int(inverse.sum())
        frame.stats["inverse_dropped_candidates"] = dropped

    @staticmethod
    def _reach(frame: Frame, o, times, views, models):
        """(the object's screen box (x0, y0, x1, y1, window px, a pixel wider) at each
        table time, unbounded where it crosses the near plane; its nearest view depth
        then): its bounding box's corners (a skinned mesh's sampled points)."""
        proj = frame.camera.projection()
        if o.skin is None:
            lo, hi = frame.gpu.bounds[o.id]
            corners = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                                for z in (lo[2], hi[2])]).T
            clip = np.einsum("kij,jn->kin", proj @ views @ models, corners)   # (K, 4, 8)
        else:
            clip = np.stack([proj @ v @ m @ object_points(o, float(tk))
                             for v, m, tk in zip(views, models, times)])
        w = clip[:, 3]
        size = np.asarray(frame.size, np.float64)[None, :, None]
        win = (clip[:, :2] / np.where(w > 0.0, w, 1.0)[:, None] * 0.5 + 0.5) * size
        boxes = np.concatenate([win.min(axis=2) - 1.0, win.max(axis=2) + 1.0], axis=1)
        behind = (w <= frame.scene.camera.near).any(axis=1)
        boxes[behind] = (-UNBOUNDED, -UNBOUNDED, UNBOUNDED, UNBOUNDED)
        return boxes, float(w.min())

    @staticmethod
    def _union(boxes: np.ndarray):
        """The box holding every one of `boxes`, or None where one is unbounded."""
        if (np.abs(boxes) >= UNBOUNDED).any():
            return None
        return (*boxes[:, :2].min(axis=0), *boxes[:, 2:].max(axis=0))

    @staticmethod
    def _tiles(box, shape, w: int, h: int) -> np.ndarray:
        """The FINE tiles (GL rows) a window box overlaps (all of them for None)."""
        sel = np.zeros(shape, bool)
        if box is None:
            sel[:] = True
            return sel
        x0, y0, x1, y1 = box
        if x1 < 0 or y1 < 0 or x0 >= w or y0 >= h:
            return sel
        c0, r0 = max(int(x0 // FINE), 0), max(int(y0 // FINE), 0)
        c1, r1 = min(int(x1 // FINE), shape[1] - 1), min(int(y1 // FINE), shape[0] - 1)
        sel[r0:r1 + 1, c0:c1 + 1] = True
        return sel
