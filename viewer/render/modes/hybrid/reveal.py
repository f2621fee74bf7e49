"""The hybrid mode's ray reveal (docs/algorithms.md 4.2): trace the masked pixels on the CPU,
shade what they reveal on the GPU exactly as the raster layer is shaded.

  reveal (host): read `ray_mask` back within the bounding box of its non-empty tiles (one
      R32UI read gives the masked pixels and their own object ids), cast one ray per
      masked pixel through its centre from the camera at the frame time with
      raytrace.RayScene (built once per scene, kept in the renderer's host state), and
      write each hit as (face row, u, v, 1 + object id) into a record texture, one
      SHADE_TILE x SHADE_TILE block per (object, screen tile) holding its pixels (layer_hits);
  reveal_shade (GPU): a fragment pass over the tiles holding those pixels, each
      fragment with its revealed object's transforms and material from a table of every
      object (one draw for all, but an image-textured object's, drawn alone with its
      GpuScene uniforms and image): it interpolates the face's
      corners (a texture of every mesh's faces, uploaded once) and shades with the same
      glsl/passes/shading.glsl and glsl/passes/motion.glsl as the G-buffer, into the composite's packed
      layer hybrid_back (D, depth, 1 + id) and hybrid_back_color (colour, 1) (a fragment
      pass, because llvmpipe draws one point per pixel at ~1.5 us; two packed targets,
      because each target written costs on llvmpipe).
      Under a still camera, a ray whose hit is the first static surface along its
      primary ray (RayScene.intersect's view) reveals what a raster of the static objects
      alone shows at its pixel: that layer, the G-buffer's kept static raster
      (viewer/render/passes/static_raster.py), is blitted in once per view (static_layer) and
      copied there, not shaded again (under a still camera, most of the revealed tiles).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import moderngl
import numpy as np

from raytrace import RayScene
from raytrace.reveal import primary_view, reveal

from world.conventions import flip_row
from viewer.render.graph.frame import Frame
from viewer.render.passes.gbuffer import GBufferPass
from viewer.render.graph.gpu_scene import TEX_KINDS, set_uniform
from viewer.render.graph.host import HostResource
from .params import HybridParams  # noqa: F401  (registers the "hybrid" group)
from viewer.render.graph.kept import KeptSlot
from viewer.render.graph.passes import FullscreenPass, Pass
from viewer.render.graph.pool import ReadBack, TexSpec
from . import reveal_kernels as kernels
from viewer.render.passes.tile_runs import TileList, clear_outside

PACKED = TexSpec(4, "f4")
STATIC_PREFIX = "static_"     # the static objects' raster: static_color, static_hybrid_front


TEXELS_PER_FACE = 6      # per corner: (position, normal.x), (normal.yz, uv)
# Whole faces to a row of the face texture (4092 texels wide): a fragment finds its face's
# six texels with one integer division, not six (llvmpipe divides lane by lane).
FACES_PER_ROW = 682
# Texture units of reveal_shade: draw() binds the pass's own textures from unit 0 up, an
# image-textured object's image goes to gpu_scene.TEXTURE_UNIT_IMAGE (7): each its own.
OBJECT_UNIT = 4
# Skinned meshes' corners at shutter open and close (SKINNED_FACES), beside the face texture.
FACE_MOTION_UNIT = 9
FACE_UNIT = 5
RECORD_UNIT = 6
# Tile side for reveal_shade's draws: finer than the tile lists' FINE, so fewer fragments
# outside the revealed pixels run the shader. llvmpipe shades 4 x 4 blocks, twice where a
# quad's diagonal crosses one; still 4 beats 8, whose blocks hold few revealed pixels
# under a moving camera.
SHADE_TILE = 4


class ObjectTable:
    """reveal_shade's per-object uniforms as a texture, a record per object id (record 0
    unused: the background), TEXELS RGBA32F texels: the columns of T(-eye) M(t), of V M at shutter
    open and close, of the normal matrix (xyz), then (albedo, specular), (albedo2,
    shininess), (texture kind, size, axis, 0) as glsl/modes/hybrid/reveal_shade.frag's OBJECT_TABLE
    reads them; OBJECTS_PER_ROW records a texture row (a power of two: the shader finds
    its record with a shift), so any number of objects fits. Image-textured objects have
    no record (a draw samples one image): they keep their own draw. The texel offsets
    reach the shader as defines (glsl_defines)."""
    MODEL, OPEN, CLOSE, NORMAL = 0, 4, 8, 12      # first texel of each matrix's columns
    MATERIAL = 15                                 # three texels of material
    TEXELS = 18
    OBJECTS_PER_ROW = 256

    @classmethod
    def glsl_defines(cls) -> dict:
        return {"OBJECT_TEXELS": cls.TEXELS, "OBJECTS_PER_ROW": cls.OBJECTS_PER_ROW,
                "OBJECT_MODEL": cls.MODEL, "OBJECT_OPEN": cls.OPEN,
                "OBJECT_CLOSE": cls.CLOSE, "OBJECT_NORMAL": cls.NORMAL,
                "OBJECT_MATERIAL": cls.MATERIAL}

    def __init__(self, ctx: moderngl.Context, scene):
        self.objects = {o.id: o for o in scene.objects}
        per_row = self.OBJECTS_PER_ROW
        rows = -(-(max(self.objects, default=0) + 1) // per_row)
        self.data = np.zeros((rows * per_row, self.TEXELS, 4), np.float32)
        for o in scene.objects:
            m, tex = o.material, o.material.texture
            mat = self.MATERIAL
            self.data[o.id, mat] = (*m.albedo, m.specular)
            self.data[o.id, mat + 1, 3] = m.shininess
            self.data[o.id, mat + 2, 0] = TEX_KINDS[tex.kind if tex else None]
            if tex is not None and tex.kind != "image":
                self.data[o.id, mat + 1, :3] = tex.albedo2
                self.data[o.id, mat + 2, 1:3] = tex.size, tex.axis
        self.texture = ctx.texture((self.TEXELS * per_row, rows), 4, dtype="f4")
        self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)

    def has_row(self, key: int) -> bool:
        """Whether key (1 + object id; 1 the background, above every id the static layer)
        is shaded from the table."""
        if key == 1:
            return True
        obj = self.objects.get(key - 1)
        return obj is not None and obj.parts is None and not (
            obj.material.texture is not None and obj.material.texture.kind == "image")

    def write(self, frame: Frame, ids):
        """The transforms of objects `ids` at the frame's time, uploaded."""
        t_open, t_close = frame.exposure
        mats = [frame.gpu.object_matrices(self.objects[i], frame.camera, frame.time, t_open,
                                          t_close, frame.object_matrices) for i in ids]
        ids = np.asarray(ids, np.int64)
        starts = (self.MODEL, self.OPEN, self.CLOSE, self.NORMAL)
        for at, m in zip(starts, zip(*mats)):     # (model, open, close, normal)
            cols = np.asarray(m, np.float32).transpose(0, 2, 1)      # (objects, column, row)
            self.data[ids, at:at + cols.shape[1], :cols.shape[2]] = cols
        self.texture.write(self.data.tobytes())

    def release(self):
        self.texture.release()


def shade_draws(keys, has_row) -> list[tuple[list[int], int, int]]:
    """reveal_shade's draws for a layer's keys [(key, first, count)], in order: (keys,
    first, count) per draw, a run of keys side by side with table rows in one draw (the
    object table: llvmpipe charges ~0.1 ms a draw however small, and reading 18 texels a
    fragment costs no more than uniforms), any other key (an image-textured object, the
    static layer) alone."""
    draws = []                  # [table?, keys, first, count]
    for key, first, count in keys:
        row = has_row(key)
        if row and draws and draws[-1][0]:
            draws[-1][1].append(key)
            draws[-1][3] += count
        else:
            draws.append([row, [key], first, count])
    return [(ks, first, count) for _, ks, first, count in draws]


class RevealState:
    """Per-scene host state: the Embree scene (built once), the faces' corners as a GPU
    texture (uploaded once), the object table, the static layer, the hit records."""

    def __init__(self, ctx: moderngl.Context, scene):
        self.ctx, self.scene = ctx, scene
        self.rays = RayScene(scene)
        self._faces: moderngl.Texture | None = None
        self._faces_motion: moderngl.Texture | None = None
        self._faces_data: np.ndarray | None = None
        self._motion_data: np.ndarray | None = None
        self._faces_posed = None
        # The skinned movers: their rows of the face texture are posed per frame.
        self.skinned = [o for o, _ in self.rays.moving if o.skin is not None]
        self.tiles: dict[str, TileList] = {}
        self.records: moderngl.Texture | None = None
        # Keys above every 1 + object id: the rays whose hit the static layer holds.
        self.static_key = max((o.id for o in scene.objects), default=0) + 2
        self._static_gbuffer = GBufferPass(prefix=STATIC_PREFIX, layout="front",
                                           static_only=True)
        self._static_stamp = None
        self._table: ObjectTable | None = None

    def object_table(self) -> ObjectTable:
        if self._table is None:
            self._table = ObjectTable(self.ctx, self.scene)
        return self._table

    def static_layer(self, frame: Frame) -> tuple[str, str]:
        """The pool names of the static objects' raster (colour, packed front) for the
        frame's view, copied in (a static-only G-buffer pass: the kept raster) when the
        view (or the textures) changed since the last."""
        view = primary_view(frame.camera, frame.time)
        if view is None:
            raise ValueError("the static layer needs a still camera's view")
        textures = self._static_gbuffer.allocate(frame)
        stamp = (view[0], tuple(t.glo for t in textures.values()))
        if stamp != self._static_stamp:
            self._static_gbuffer.execute(frame)
            self._static_stamp = stamp
        return self._static_gbuffer.produces

    def face_texture(self) -> moderngl.Texture:
        if self._faces is None:
            corners = self.rays.surfaces.gpu_corners().reshape(-1, TEXELS_PER_FACE, 4)
            if len(corners) >= 1 << 24:
                raise ValueError("the hybrid reveal shades at most 2^24 faces")
            rows = max(1, -(-len(corners) // FACES_PER_ROW))
            data = np.zeros((rows * FACES_PER_ROW, TEXELS_PER_FACE, 4), np.float32)
            data[:len(corners)] = corners
            self._faces = self.ctx.texture((FACES_PER_ROW * TEXELS_PER_FACE, rows), 4,
                                           data.tobytes(), dtype="f4")
            self._faces.filter = (moderngl.NEAREST, moderngl.NEAREST)
            if self.skinned:
                # Rigid corners are where they are at every time (M(t) moves them).
                self._faces_data = data
                c = data.reshape(-1, 3, 2, 4)
                self._motion_data = np.zeros_like(c)
                self._motion_data[:, :, 0, :3] = self._motion_data[:, :, 1, :3] = c[:, :, 0, :3]
                self._motion_data = self._motion_data.reshape(data.shape)
                self._faces_motion = self.ctx.texture(self._faces.size, 4,
                                                      self._motion_data.tobytes(), dtype="f4")
                self._faces_motion.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return self._faces

    def pose_faces(self, t: float, t_open: float, t_close: float):
        """The skinned movers' faces posed for a frame at t: their corners (position,
        normal) at t in the face texture, their positions at shutter open and close in
        the motion texture (SKINNED_FACES: per corner (open, 0), (close, 0)); only their
        rows are written."""
        key = tuple(o.skin.stamp(t, t_open, t_close) for o in self.skinned)
        if not self.skinned or self._faces_posed == key:
            return
        self.face_texture()
        table = self.rays.surfaces
        width = FACES_PER_ROW * TEXELS_PER_FACE
        motion = self._motion_data
        for o in self.skinned:
            first = int(table.face_offset[o.id])
            faces = o.mesh.faces
            pos, nrm = o.skin.deformed(t)
            rows = slice(first, first + len(faces))
            d = self._faces_data[rows].reshape(len(faces), 3, 2, 4)
            d[:, :, 0, :3] = pos[faces]
            d[:, :, 0, 3] = nrm[faces][:, :, 0]
            d[:, :, 1, :2] = nrm[faces][:, :, 1:]
            m = motion[rows].reshape(len(faces), 3, 2, 4)
            m[:, :, 0, :3] = o.vertices_at(t_open)[faces]
            m[:, :, 1, :3] = o.vertices_at(t_close)[faces]
            self._faces_data[rows] = d.reshape(len(faces), TEXELS_PER_FACE, 4)
            motion[rows] = m.reshape(len(faces), TEXELS_PER_FACE, 4)
            r0, r1 = first // FACES_PER_ROW, -(-(first + len(faces)) // FACES_PER_ROW)
            span = slice(r0 * FACES_PER_ROW, r1 * FACES_PER_ROW)
            vp = (0, r0, width, r1 - r0)
            self._faces.write(self._faces_data[span].tobytes(), viewport=vp)
            self._faces_motion.write(motion[span].tobytes(), viewport=vp)
        self._faces_posed = key

    def records_texture(self, shape: tuple[int, int]) -> moderngl.Texture:
        """The hit-record texture, at least `shape` (rows, columns); grown in whole
        powers of two of rows so that it is seldom reallocated."""
        tex = self.records
        h, w = shape
        if tex is None or tex.size[0] < w or tex.size[1] < h:
            if tex is not None:
                tex.release()
            rows = 1 << max(4, (h - 1).bit_length())
            tex = self.records = self.ctx.texture((w, rows), 4, dtype="f4")
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return tex

    def tile_list(self, name: str = "shade") -> TileList:
        """The revealed pixels' tile list (or another kept list, by name)."""
        if name not in self.tiles:
            self.tiles[name] = TileList(self.ctx)
        return self.tiles[name]

    def release(self):
        if self._faces is not None:
            self._faces.release()
            self._faces = None
        if self._faces_motion is not None:
            self._faces_motion.release()
            self._faces_motion = None
        if self._table is not None:
            self._table.release()
            self._table = None
        for tl in self.tiles.values():
            tl.release()
        if self.records is not None:
            self.records.release()
            self.records = None
        self.tiles.clear()


@dataclass
class LayerHits:
    """One layer's traced pixels: their hit records in blocks (layer_hits), the keys
    (1 + object id, 1 = the ray left the scene) present, and the tiles of each key."""
    records: np.ndarray
    keys: list[tuple[int, int, int]]   # (key, first, count) of each key's run in `tiles`
    tiles: np.ndarray            # (n, 2) SHADE_TILE tiles (GL orientation) of each key's pixels


KEPT_REVEAL = KeptSlot("hybrid_reveal", RevealState, "the reveal's Embree scene and tables")
# This frame's reveal: the pixels traced (image (i, j)), their hits (None: nothing traced),
# and what `hmblur bench` needs to time bare Embree on the same primary rays
# (raytrace.bench: rayscene, camera, pixels, own, t).
MASKED_PIXELS = HostResource("masked_pixels", np.ndarray, "(n, 2) image (i, j) traced")
REVEAL_HITS = HostResource("reveal_hits", LayerHits, "the traced pixels' hit records",
                           optional=True)
REVEAL_BATCH = HostResource("reveal_batch", dict, "the primary rays, for hmblur bench")


def reveal_state(frame: Frame) -> RevealState:
    return frame.kept.get_or_make(KEPT_REVEAL, lambda: RevealState(frame.ctx, frame.scene),
                                  lambda rs: rs.scene is frame.scene and rs.ctx is frame.ctx)


def read_masked_pixels(frame: Frame) -> tuple[np.ndarray, np.ndarray]:
    """The masked pixels and own ids, reading back only the box that the range check wrote
    (the ray mask is 0 elsewhere: ResourcePool's record), or the whole mask where that is
    not known."""
    w, h = frame.size
    box = frame.pool.written_box("ray_mask")
    if box is None:                                     # nothing written since a clear
        return np.zeros((0, 2), np.int64), np.zeros(0, np.uint32)
    i0, y0, i1, y1 = box if box != "unknown" else (0, 0, w, h)   # GL pixels
    data = frame.pool.read_back("ray_mask", viewport=(i0, y0, i1 - i0, y1 - y0),
                                components=1, dtype="u4")
    gl_rows = np.frombuffer(data, np.uint32).reshape(y1 - y0, i1 - i0)
    return kernels.nonzero_pixels(gl_rows, i0, flip_row(y1 - 1, h))   # the top row's image row


def frame_models(frame: Frame, moving) -> list | None:
    """M(t) of the objects of `moving` ((object, Embree scene) pairs) as this frame's
    G-buffer made them (GpuScene.object_matrices' memo), or None where it did not (the
    reveal then asks each object)."""
    memo = frame.object_matrices
    models = [memo.get(("model", o.id, frame.time)) for o, _ in moving]
    return None if any(m is None for m in models) else models


BLOCKS_PER_ROW = 256     # record blocks (SHADE_TILE x SHADE_TILE) per row; both powers of 2


def layer_hits(pixels: np.ndarray, layer, height: int, static_key: int | None = None
               ) -> LayerHits | None:
    """The revealed layer as hit records (face row, u, v, key), key = 1 + object id, or
    static_key where given for the hits the static layer holds (layer.static_view), one
    SHADE_TILE x SHADE_TILE block per (key, screen tile) holding its pixels, blocks in
    rows of BLOCKS_PER_ROW, sorted by key: each key's draw covers only its own run of
    tiles (reveal_kernels.pack_blocks); None when nothing was traced."""
    if not len(pixels):
        return None
    gx, gy, key, face = kernels.record_inputs(
        pixels, height, layer.object_id, layer.prim_id, layer.table.face_offset,
        layer.static_view, -1 if static_key is None else static_key)
    records, _, tiles, runs = kernels.pack_blocks(
        gx, gy, key, face, layer.barycentrics, SHADE_TILE.bit_length() - 1,
        BLOCKS_PER_ROW.bit_length() - 1)
    return LayerHits(records, [tuple(r) for r in runs.tolist()], tiles)


class RevealTrace(Pass):
    """Host side: mask read-back, ray casting, and the hits' records."""
    name = "reveal"
    runs_on = "cpu"
    inputs = ("ray_mask",)
    host_outputs = (MASKED_PIXELS, REVEAL_HITS, REVEAL_BATCH)
    reads_back = (ReadBack("ray_mask"),)

    def execute(self, frame: Frame):
        p = frame.params["hybrid"]
        t0 = time.perf_counter()
        st = reveal_state(frame)
        pixels, own = read_masked_pixels(frame)
        t1 = time.perf_counter()
        result = None
        skin0 = st.rays.skin_ms
        if len(pixels) and p.trace:
            result = reveal(st.rays, frame.camera, frame.time, pixels, own,
                            max_depth=p.max_depth, threads=p.threads or None,
                            matrices=frame_models(frame, st.rays.moving))
        t2 = time.perf_counter()
        hits = (layer_hits(pixels, result.layer, frame.size[1], st.static_key)
                if result else None)
        t3 = time.perf_counter()
        s = frame.stats
        s["masked_pixels"] = int(len(pixels))
        s["rays"] = int(result.rays) if result else 0
        s["revealed_pixels"] = int(result.pixels_hit) if result else 0
        # Revealed surfaces copied from the static objects' raster (RevealState.static_layer).
        s["static_layer_hits"] = np.count_nonzero(result.layer.static_view) if result else 0
        s["restarts"] = int(result.restarts) if result else 0
        s["unresolved"] = int(result.unresolved) if result else 0
        s["reveal_readback_ms"] = (t1 - t0) * 1e3
        s["reveal_trace_ms"] = (t2 - t1) * 1e3
        s["reveal_pack_ms"] = (t3 - t2) * 1e3
        s["reveal_ms"] = (t3 - t0) * 1e3
        if st.skinned:     # (within the tracing: skinned movers' Embree scenes rebuilt)
            s["reveal_skin_ms"] = st.rays.skin_ms - skin0
        frame.host.put(MASKED_PIXELS, pixels)
        frame.host.put(REVEAL_HITS, hits)
        frame.host.put(REVEAL_BATCH, {"rayscene": st.rays, "camera": frame.camera,
                                      "pixels": pixels, "own": own, "t": frame.time})


BACK = ("hybrid_back", "hybrid_back_color")    # glsl/modes/hybrid/hybrid_layers.glsl's back layer


class RevealShade(FullscreenPass):
    """GPU side: the revealed layer's displacement, depth, id and colour at the masked
    pixels, packed for the composite (BACK), everything else cleared to 0, 'nothing
    revealed'."""
    name = "reveal_shade"
    fragment = "modes/hybrid/reveal_shade.frag"
    host_inputs = (REVEAL_HITS,)
    # BACK; the static layer, copied in where a hit takes its pixel from it
    produces = (*BACK, *(STATIC_PREFIX + n for n in GBufferPass(layout="front").produces))

    def defines(self, frame: Frame):
        return {**frame.gpu.light_defines(), **ObjectTable.glsl_defines(),
                "FACES_PER_ROW": FACES_PER_ROW, "TEXELS_PER_FACE": TEXELS_PER_FACE,
                "SKINNED_FACES": int(bool(reveal_state(frame).skinned))}

    def outputs(self, frame: Frame):
        return {n: PACKED for n in BACK}

    def execute(self, frame: Frame):
        cam, gpu = frame.camera, frame.gpu
        st = reveal_state(frame)
        t = frame.time
        t_open, t_close = frame.exposure
        names = BACK
        tl = st.tile_list()
        hits = frame.host.get(REVEAL_HITS)
        if hits is None:
            tl.set(np.zeros((0, 2), np.int64), SHADE_TILE, frame.size, BLOCKS_PER_ROW)
            clear_outside(frame, names, tl)     # last frame's tiles
            frame.pool.mark_tiles(names, tl)
            return
        # The tiles holding the traced pixels; each key's draw keeps its own run. Its
        # draws together write every pixel of them (records: the key's own, 0 "no ray",
        # -1 another key's), so only last frame's other tiles are cleared.
        tl.set(hits.tiles, SHADE_TILE, frame.size, BLOCKS_PER_ROW,
               cuts=[first for _, first, _ in hits.keys])
        clear_outside(frame, names, tl)
        records = st.records_texture(hits.records.shape[:2])
        h, w = hits.records.shape[:2]
        records.write(hits.records.tobytes(), viewport=(0, 0, w, h))
        st.face_texture().use(FACE_UNIT)      # draw() binds its textures from unit 0
        if st.skinned:
            st.pose_faces(t, t_open, t_close)
            st._faces_motion.use(FACE_MOTION_UNIT)
        records.use(RECORD_UNIT)
        objects = {o.id: o for o in frame.scene.objects}
        if any(key == st.static_key for key, _, _ in hits.keys):
            colour, front = st.static_layer(frame)
        table = st.object_table()
        draws = shade_draws(hits.keys, table.has_row)
        ids = [k - 1 for k, _, _ in hits.keys if k > 1 and table.has_row(k)]
        if ids:
            table.write(frame, ids)
        table.texture.use(OBJECT_UNIT)
        for keys, first, count in draws:
            key = keys[0]
            static, from_table = key == st.static_key, table.has_row(key)
            variant = {"STATIC_LAYER": int(static), "OBJECT_TABLE": int(from_table)}
            textures = {"u_static_front": front, "u_static_color": colour} if static else {}
            prog = self.program(frame, tl.vertex_shader, variant)   # the draw's, cached
            set_uniform(prog, "u_hits", RECORD_UNIT)
            if not static:
                gpu.bind_camera(prog, cam, t, frame.size)
                set_uniform(prog, "u_background", frame.scene.background)
                gpu.bind_lights(prog)
                set_uniform(prog, "u_faces", FACE_UNIT)
            if st.skinned and not static:
                set_uniform(prog, "u_faces_motion", FACE_MOTION_UNIT)
            if from_table:
                set_uniform(prog, "u_objects", OBJECT_UNIT)
                self.draw(frame, names, textures, tiles=tl.part(first, count), clear=False,
                          defines=variant)
                continue
            if static:
                self.draw(frame, names, textures, tiles=tl.part(first, count), clear=False,
                          defines=variant)
                continue
            # An object drawn alone (an image, or parts of several materials): each part
            # shades the faces of its range, discarding the others' (their draw writes them).
            obj = objects[key - 1]
            gpu.bind_object(prog, obj, cam, t, t_open, t_close, frame.object_matrices)
            offset = int(st.rays.surfaces.face_offset[obj.id])
            for lo, n, material in obj.parts or [(0, len(obj.mesh.faces), None)]:
                if material is not None:
                    gpu.bind_material(prog, obj, material)
                set_uniform(prog, "u_face_range", (offset + lo, offset + lo + n))
                self.draw(frame, names, textures, tiles=tl.part(first, count), clear=False,
                          defines=variant)
        frame.stats["shade_draws"] = len(draws)
        frame.pool.mark_tiles(names, tl)


def reveal_passes() -> list:
    return [RevealTrace(), RevealShade()]
