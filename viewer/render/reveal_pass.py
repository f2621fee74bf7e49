"""The hybrid mode's ray reveal (ALGORITHMS.md 4.2): trace the masked pixels on the CPU,
shade what they reveal on the GPU exactly as the raster layer is shaded.

  reveal (host): read `ray_mask` back within the bounding box of its non-empty tiles (one
      R32UI read gives the masked pixels and their own object ids), cast one ray per masked pixel through its centre from the camera at
      the frame time with raytrace.RayScene (built once per scene, kept in the renderer's
      host state), and pack the hits, grouped by object, into a vertex buffer;
  reveal_shade (GPU): draw one point per revealed pixel into revealed_color / _depth / _id
      / _velocity (and revealed2_* for a second layer), one draw per revealed object with
      that object's GpuScene uniforms, so glsl/shading.glsl and glsl/motion.glsl give the
      same colour, depth and displacement as the G-buffer would.
"""
from __future__ import annotations

import time

import moderngl
import numpy as np

from raytrace import RayScene

from ..conventions import BACKGROUND_DEPTH, glsl_defines, to_image
from .blur_common import max_radius_px
from .frame import Frame
from .gpu_scene import MAX_LIGHTS, set_uniform
from .hybrid_params import HybridParams  # noqa: F401  (registers the "hybrid" group)
from .passes import Pass
from .pool import TexSpec

PACKED = TexSpec(4, "f4")
LAYER_SPECS = {"color": TexSpec(4, "f4"), "depth": TexSpec(1, "f4"),
               "id": TexSpec(1, "u4"), "velocity": TexSpec(2, "f4")}
MAX_LAYERS = 2
# Per revealed pixel: image (i, j), mesh-space position, mesh-space normal, uv.
VERTEX_FORMAT = (("in_pixel", 2), ("in_local", 3), ("in_normal", 3), ("in_uv", 2))
STATE_KEY = "hybrid_reveal"


def layer_prefix(k: int) -> str:
    """Texture prefix of revealed layer k (0-based): revealed_, revealed2_, ..."""
    return "revealed_" if k == 0 else f"revealed{k + 1}_"


def layer_names(k: int) -> tuple[str, ...]:
    return tuple(layer_prefix(k) + n for n in LAYER_SPECS)


class RevealState:
    """Per-scene host state: the Embree scene (built once) and the GL objects the points
    are drawn from (grown, never reallocated per frame)."""

    def __init__(self, ctx: moderngl.Context, scene):
        self.ctx, self.scene = ctx, scene
        self.rays = RayScene(scene)
        self.buffers: dict[int, moderngl.Buffer] = {}
        self.vaos: dict[tuple[int, int], moderngl.VertexArray] = {}
        self.batches: list = []        # per layer: (ranges, count) of the current frame
        self.boxes: list = []          # per layer: GL pixel box around its points, or None

    def upload(self, k: int, data: np.ndarray) -> moderngl.Buffer:
        nbytes = max(data.nbytes, 4)
        buf = self.buffers.get(k)
        if buf is None or buf.size < nbytes:
            for key in [key for key in self.vaos if key[1] == k]:
                self.vaos.pop(key).release()
            if buf is not None:
                buf.release()
            buf = self.buffers[k] = self.ctx.buffer(reserve=max(nbytes, 1 << 16))
        if data.nbytes:
            buf.write(data.tobytes())
        return buf

    def vao(self, prog: moderngl.Program, k: int) -> moderngl.VertexArray:
        key = (prog.glo, k)
        if key not in self.vaos:
            fmt, names = [], []
            for name, n in VERTEX_FORMAT:
                if name in prog:
                    fmt.append(f"{n}f")
                    names.append(name)
                else:
                    fmt.append(f"{4 * n}x")        # dropped by the compiler: skip its bytes
            self.vaos[key] = self.ctx.vertex_array(
                prog, [(self.buffers[k], " ".join(fmt), *names)])
        return self.vaos[key]

    def release(self):
        for v in self.vaos.values():
            v.release()
        for b in self.buffers.values():
            b.release()
        self.vaos.clear(), self.buffers.clear()


def reveal_state(frame: Frame) -> RevealState:
    state = frame.host.setdefault("state", {})
    rs = state.get(STATE_KEY)
    if rs is None or rs.scene is not frame.scene or rs.ctx is not frame.ctx:
        if rs is not None:
            rs.release()
        rs = state[STATE_KEY] = RevealState(frame.ctx, frame.scene)
    return rs


def masked_pixels(ray_mask: np.ndarray, origin=(0, 0)) -> tuple[np.ndarray, np.ndarray]:
    """(n, 2) image coordinates (i, j) of the masked pixels in row-major image order and
    their own object ids, from (a window of) `ray_mask` in image orientation whose top-left
    pixel is image pixel `origin`."""
    flat = ray_mask.reshape(-1)
    idx = np.flatnonzero(flat)
    w = ray_mask.shape[1]
    return np.stack([idx % w + origin[0], idx // w + origin[1]], axis=1), flat[idx]


def read_masked_pixels(frame: Frame) -> tuple[np.ndarray, np.ndarray]:
    """The masked pixels and own ids, reading back only the bounding box of the tiles that
    hold any (`ray_mask_tiles`, a few hundred texels), not the whole id-sized mask."""
    tiles = frame.read("ray_mask_tiles")[..., 1]           # image orientation
    rows, cols = np.nonzero(tiles)
    if not len(rows):
        return np.zeros((0, 2), np.int64), np.zeros(0, np.uint32)
    k = max_radius_px(frame)                                # the tile size
    w, h = frame.size
    i0, i1 = cols.min() * k, min((cols.max() + 1) * k, w)
    # Tiles count from the GL origin (bottom-left): image row r of tiles covers GL rows
    # [(T - 1 - r) k, (T - r) k), cut at the top of the screen.
    t = tiles.shape[0]
    y0, y1 = (t - 1 - rows.max()) * k, min((t - rows.min()) * k, h)
    fbo = frame.pool.framebuffer(("ray_mask",))
    data = fbo.read(viewport=(i0, y0, i1 - i0, y1 - y0), components=1, dtype="u4")
    window = to_image(np.frombuffer(data, np.uint32).reshape(y1 - y0, i1 - i0))
    return masked_pixels(window, origin=(i0, h - y1))


def gl_box(pixels_ij: np.ndarray, height: int) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) in GL pixels around image pixels (i, j) (row j from the top)."""
    i, j = pixels_ij[:, 0], pixels_ij[:, 1]
    return (int(i.min()), int(height - 1 - j.max()), int(i.max()) + 1, int(height - j.min()))


def pack_layer(pixels: np.ndarray, layer) -> tuple[np.ndarray, list[tuple[int, int, int]]]:
    """Vertex data of one revealed layer, grouped by object id (0 = the ray left the
    scene), and the (object id, first, count) ranges to draw. Untraced rows are left out."""
    rows = np.flatnonzero(layer.traced)
    ids = layer.object_id[rows]
    order = rows[np.argsort(ids, kind="stable")]
    data = np.empty((len(order), 10), dtype=np.float32)
    data[:, 0:2] = pixels[order]
    data[:, 2:5] = layer.local_position[order]
    data[:, 5:8] = layer.local_normal[order]
    data[:, 8:10] = layer.uv[order]
    sorted_ids = layer.object_id[order]
    uniq, first, count = np.unique(sorted_ids, return_index=True, return_counts=True)
    return data, [(int(u), int(f), int(c)) for u, f, c in zip(uniq, first, count)]


class RevealTrace(Pass):
    """Host side: mask read-back, ray casting, vertex packing and upload."""
    name = "reveal"
    inputs = ("ray_mask", "ray_mask_tiles")
    produces = ("reveal_hits",)          # host-side: the vertex buffers in RevealState

    def execute(self, frame: Frame):
        p = frame.params["hybrid"]
        t0 = time.perf_counter()
        st = reveal_state(frame)
        pixels, own = read_masked_pixels(frame)
        t1 = time.perf_counter()
        st.batches, st.boxes = [], []
        result = None
        if len(pixels) and p.trace:
            result = st.rays.reveal(frame.camera, frame.time, pixels, own, layers=p.layers,
                                    max_depth=p.max_depth, threads=p.threads or None)
        t2 = time.perf_counter()
        for k in range(p.layers):
            if result is None:
                st.batches.append(([], 0))
                continue
            data, ranges = pack_layer(pixels, result.layers[k])
            st.upload(k, data)
            st.batches.append((ranges, len(data)))
            st.boxes.append(gl_box(data[:, :2], frame.size[1]) if len(data) else None)
        t3 = time.perf_counter()
        s = frame.stats
        s["masked_pixels"] = int(len(pixels))
        s["rays"] = int(result.rays) if result else 0
        s["revealed_pixels"] = int(result.pixels_hit) if result else 0
        s["restarts"] = int(result.restarts) if result else 0
        s["unresolved"] = int(result.unresolved) if result else 0
        s["reveal_readback_ms"] = (t1 - t0) * 1e3
        s["reveal_trace_ms"] = (t2 - t1) * 1e3
        s["reveal_upload_ms"] = (t3 - t2) * 1e3
        s["reveal_ms"] = (t3 - t0) * 1e3
        # What `hmblur bench` needs to time bare Embree on the same primary rays.
        frame.host["reveal_batch"] = {"rayscene": st.rays, "camera": frame.camera,
                                      "pixels": pixels, "t": frame.time}


def packed_names(k: int) -> tuple[str, str]:
    """The composite's packed motion and colour textures of revealed layer k
    (glsl/hybrid_layers.glsl): hybrid_back, hybrid_back_color; hybrid_back2, ..."""
    tag = "hybrid_back" if k == 0 else f"hybrid_back{k + 1}"
    return tag, tag + "_color"


class RevealShade(Pass):
    """GPU side: the revealed layers' colour, depth, id and displacement at the masked
    pixels, everything else cleared to 'nothing revealed' (alpha 0, the background's
    depth, id 0); and the same packed for the composite (packed_names). Every layer up to
    MAX_LAYERS is produced (the deeper ones stay cleared when fewer are traced), so the
    pipeline's textures do not depend on the `hybrid.layers` setting."""
    name = "reveal_shade"
    inputs = ("reveal_hits",)
    produces = tuple(n for k in range(MAX_LAYERS) for n in (*layer_names(k), *packed_names(k)))

    def outputs(self, frame: Frame):
        out = {}
        for k in range(MAX_LAYERS):
            out.update({n: LAYER_SPECS[n.split("_", 1)[1]] for n in layer_names(k)})
            out.update({n: PACKED for n in packed_names(k)})
        return out

    @staticmethod
    def clear(frame: Frame, names: tuple[str, ...]):
        """Clear where the last frame drew (ResourcePool.clear): everything to 0, the depth
        (names[1]) to the background's."""
        frame.pool.clear(names[:1] + names[2:])
        frame.pool.clear(names[1:2], (BACKGROUND_DEPTH, 0.0, 0.0, 0.0))

    def execute(self, frame: Frame):
        ctx, cam, gpu = frame.ctx, frame.camera, frame.gpu
        st = reveal_state(frame)
        t = frame.time
        t_open, t_close = frame.exposure
        prog = frame.programs.get("reveal_points.vert", "reveal_shade.frag",
                                  {**glsl_defines(), "MAX_LIGHTS": MAX_LIGHTS})
        for k in range(MAX_LAYERS):
            names = (*layer_names(k), *packed_names(k))
            self.clear(frame, names)
            ranges, count = st.batches[k] if k < len(st.batches) else ([], 0)
            if not count:
                continue
            frame.pool.mark_written(names, st.boxes[k])
            fbo = frame.pool.framebuffer(names)
            fbo.use()
            fbo.viewport = (0, 0) + fbo.size
            ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
            gpu.bind_camera(prog, cam, t, t_open, t_close, frame.size)
            set_uniform(prog, "u_background", frame.scene.background)
            set_uniform(prog, "u_max_disp", 2.0 * max_radius_px(frame))
            gpu.bind_lights(prog)
            vao = st.vao(prog, k)
            objects = {o.id: o for o in frame.scene.objects}
            for oid, first, n in ranges:
                set_uniform(prog, "u_miss", oid == 0)
                if oid:
                    gpu.bind_object(prog, objects[oid], t, t_open, t_close)
                vao.render(moderngl.POINTS, vertices=n, first=first)


def reveal_passes() -> list:
    return [RevealTrace(), RevealShade()]
