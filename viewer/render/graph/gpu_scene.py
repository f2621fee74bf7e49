"""The scene on the GPU: one vertex buffer per object (mesh space, uploaded once), image
textures, and the uniforms of materials and lights. Both the raster G-buffer pass and the
shading of ray-revealed surfaces set their uniforms here, so both layers shade the same.
"""
from __future__ import annotations

import math

import moderngl
import numpy as np

from world import transforms as tf
from world.conventions import to_image
from world.errors import SceneError
from world.scene import Material, Scene, SceneObject
from viewer.render.graph import depth

# The shaders' light arrays hold a multiple of this many lights (the define MAX_LIGHTS):
# one program per 16, not per light count.
LIGHT_SLOTS = 16
# Uniform vectors left to the rest of a fragment shader beside the light arrays.
OTHER_UNIFORM_VECTORS = 64
TEX_KINDS = {None: 0, "checker": 1, "stripes": 2, "image": 3}
TEXTURE_UNIT_IMAGE = 7
# Lights past the uniform storage: a texture (glsl/passes/shading.glsl LIGHTS_TEXTURE) on this
# unit, two texels a light, this many lights a row.
LIGHT_UNIT = 8
LIGHTS_PER_ROW = 1024


def vertex_data(obj: SceneObject) -> np.ndarray:
    """Unshared triangles: (3m, 8) float32 of mesh-space position, normal and UV. Flat
    shading gets the face normal at all three corners, smooth the trimesh vertex normals."""
    m = obj.mesh
    corners = m.faces.reshape(-1)
    pos = m.vertices[corners]
    if obj.shading == "flat":
        nrm = np.repeat(m.face_normals, 3, axis=0)
    else:
        nrm = m.vertex_normals[corners]
    uv = m.uv[corners] if m.uv is not None else np.zeros((len(corners), 2))
    return np.hstack([pos, nrm, uv]).astype(np.float32)


# A vertex's attributes in the G-buffer program (glsl/passes/gbuffer.vert): (name, floats). A
# rigid object's buffer holds the first three; its positions at the exposure's times are
# its one position (the model matrices move it). A skinned object's holds them all, posed
# per draw: at t, shutter open and close, and the path's quarter points (SEGMENTS 4).
ATTRIBUTES = (("in_position", 3), ("in_normal", 3), ("in_uv", 2), ("in_position_open", 3),
              ("in_position_close", 3), ("in_path1", 3), ("in_path3", 3))
RIGID_FLOATS = 8
SKINNED_FLOATS = sum(n for _, n in ATTRIBUTES)
# Where a rigid buffer finds each attribute (float offset): the exposure's positions are
# the position.
RIGID_OFFSETS = {"in_position": 0, "in_normal": 3, "in_uv": 6, "in_position_open": 0,
                 "in_position_close": 0, "in_path1": 0, "in_path3": 0}


def skinned_vertex_data(obj: SceneObject, t: float, t_open: float, t_close: float,
                        times) -> np.ndarray:
    """A skinned object's unshared triangles posed for one draw: (3m, SKINNED_FLOATS)
    float32 of ATTRIBUTES (the path's quarter points where `times` has 5, else the
    shutter's ends again)."""
    m = obj.mesh
    corners = m.faces.reshape(-1)
    pos, nrm = obj.skin.deformed(t)
    uv = m.uv[corners] if m.uv is not None else np.zeros((len(corners), 2))
    quarter = (times[1], times[3]) if times is not None and len(times) == 5 else (t_open, t_close)
    others = [obj.vertices_at(tk)[corners] for tk in (t_open, t_close, *quarter)]
    return np.hstack([pos[corners], nrm[corners], uv, *others]).astype(np.float32)


def materials_of(obj: SceneObject) -> list[Material]:
    """Every material an object draws with: its parts', or its one."""
    return [m for _, _, m in obj.parts] if obj.parts else [obj.material]


def mat(m: np.ndarray) -> bytes:
    """A numpy matrix (column-vector convention) as GLSL expects it (column-major)."""
    return np.asarray(m, dtype=np.float32).T.tobytes()


def set_uniform(prog: moderngl.Program, name: str, value):
    u = prog.get(name, None)     # (`name in prog` would walk every member: no __contains__)
    if u is None:
        return  # the compiler removed an unused uniform
    if isinstance(value, np.ndarray):
        value = mat(value) if value.ndim == 2 else tuple(float(x) for x in value)
    # A program keeps its uniforms between draws: skip the write when nothing changed
    # (most of a frame's ~230 uniforms do not, frame after frame).
    last = prog.extra if isinstance(prog.extra, dict) else {}
    if name in last and last[name] == value:
        return
    if isinstance(value, bytes):
        u.write(value)
    else:
        u.value = value
    last[name] = value
    prog.extra = last


def light_slots(ctx: moderngl.Context, scene: Scene) -> int:
    """The length of the shaders' light arrays for `scene` (MAX_LIGHTS): its light count
    rounded up to LIGHT_SLOTS, as long as the driver's uniform storage holds them (two
    vec3 arrays: 2016 lights on llvmpipe, 480 where it holds 1024 vectors, 96 at GL's
    least, 256); 0 beyond that: the lights then go in a texture (light_texture), any
    number of them (docs/scene-format.md), up to LIGHTS_PER_ROW times the texture height limit."""
    n = len(scene.lights)
    slots = max(LIGHT_SLOTS, -(-n // LIGHT_SLOTS) * LIGHT_SLOTS)
    vectors = int(ctx.info.get("GL_MAX_FRAGMENT_UNIFORM_VECTORS") or 256)
    most = (vectors - OTHER_UNIFORM_VECTORS) // 2 // LIGHT_SLOTS * LIGHT_SLOTS
    if slots <= most:
        return slots
    rows = int(ctx.info.get("GL_MAX_TEXTURE_SIZE") or 1024)
    if n > rows * LIGHTS_PER_ROW:
        raise SceneError(scene.path or scene.name, "lights",
                         f"{n} lights; this GL driver holds at most {rows * LIGHTS_PER_ROW}")
    return 0


def light_texels(scene: Scene) -> np.ndarray:
    """The lights as the texture LIGHTS_TEXTURE reads: light k's direction at texel
    (2 (k % LIGHTS_PER_ROW), k // LIGHTS_PER_ROW), its colour beside it; (rows, 2 *
    LIGHTS_PER_ROW, 3) float32."""
    n = len(scene.lights)
    rows = max(1, -(-n // LIGHTS_PER_ROW))
    texels = np.zeros((rows * LIGHTS_PER_ROW, 2, 3), np.float32)
    for k, light in enumerate(scene.lights):
        texels[k] = light.direction, light.color
    return texels.reshape(rows, 2 * LIGHTS_PER_ROW, 3)


def _normal_matrix(obj: SceneObject, model: np.ndarray) -> np.ndarray:
    """tf.normal_matrix(model) (read-only), kept on the object for its last 3x3: an object
    that does not turn keeps it from frame to frame (np.linalg.inv: ~5-10 us a call)."""
    m3 = model[:3, :3].tobytes()
    kept = obj.__dict__.get("_normal_memo")
    if kept is None or kept[0] != m3:
        n = tf.normal_matrix(model)
        n.flags.writeable = False
        kept = obj.__dict__["_normal_memo"] = (m3, n)
    return kept[1]


class GpuScene:
    def __init__(self, ctx: moderngl.Context, scene: Scene):
        self.max_lights = light_slots(ctx, scene)
        self.ctx, self.scene = ctx, scene
        self.light_texture = None
        if not self.max_lights:
            texels = light_texels(scene)
            self.light_texture = ctx.texture(texels.shape[1::-1], 3, texels.tobytes(),
                                             dtype="f4")
            self.light_texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        # Rigid meshes uploaded once (one buffer for the objects that share a mesh); a
        # skinned one's buffer is posed per draw (pose()).
        self.buffers, shared = [], {}
        for o in scene.objects:
            if o.skin is not None:
                self.buffers.append(ctx.buffer(reserve=3 * len(o.mesh.faces) * SKINNED_FLOATS * 4))
                continue
            key = (id(o.mesh), o.shading)
            if key not in shared:
                shared[key] = ctx.buffer(vertex_data(o).tobytes())
            self.buffers.append(shared[key])
        self._posed: dict[int, tuple] = {}          # object id -> the times its buffer holds
        # Image textures by the Texture they draw (one object may draw several: parts).
        self.images: dict[int, moderngl.Texture] = {}
        limit = int(ctx.info.get("GL_MAX_TEXTURE_SIZE") or 1024)
        for o in scene.objects:
            for m in materials_of(o):
                tex = m.texture
                if tex is None or tex.kind != "image" or id(tex) in self.images:
                    continue
                h, w = tex.image.shape[:2]
                if max(w, h) > limit:        # (GL would leave the texture empty: black)
                    raise SceneError(scene.path or scene.name,
                                     f"objects[{o.id}] ({o.name}).material.texture.path",
                                     f"an image of at most {limit} px a side (this GL "
                                     f"driver's limit), got {w}x{h}")
                # (UV origin bottom-left: GL rows, the image's rows flipped)
                img = to_image(tex.image).astype(np.float32, copy=False)
                t = ctx.texture((img.shape[1], img.shape[0]), 3, np.ascontiguousarray(img),
                                dtype="f4")      # (the array itself: no bytes copy)
                t.filter = (moderngl.LINEAR, moderngl.LINEAR)
                t.repeat_x = t.repeat_y = True
                self.images[id(tex)] = t
        self._vaos: dict[tuple[int, int], moderngl.VertexArray] = {}
        # Local bounding boxes (lo, hi) of the meshes as loaded, and their centres
        # (homogeneous: (x, y, z, 1)) for the draw order.
        self.bounds = {o.id: (o.mesh.vertices.min(0), o.mesh.vertices.max(0))
                       if len(o.mesh.vertices) else (np.zeros(3), np.zeros(3))
                       for o in scene.objects}
        self._centres = {i: np.append((lo + hi) / 2, 1.0) for i, (lo, hi) in self.bounds.items()}

    def front_to_back(self, eye: np.ndarray, t: float) -> list[SceneObject]:
        """Objects nearest first, so the depth test rejects hidden fragments before they are
        shaded (software GL shades every fragment that passes). Ties keep file order."""
        def distance(o):
            d = (o.matrix(t) @ self._centres[o.id])[:3] - eye
            return math.sqrt(d.dot(d))          # np.linalg.norm's value, without its checks
        return sorted(self.scene.objects, key=lambda o: (distance(o), o.id))

    def vao(self, prog: moderngl.Program, obj: SceneObject) -> moderngl.VertexArray:
        key = (prog.glo, obj.id)
        if key not in self._vaos:
            # Each attribute the program uses, from its place in the object's buffer
            # (attributes the compiler dropped are left out).
            rigid = obj.skin is None
            floats = RIGID_FLOATS if rigid else SKINNED_FLOATS
            content, at = [], 0
            for name, n in ATTRIBUTES:
                offset = RIGID_OFFSETS[name] if rigid else at
                at += n
                if prog.get(name, None) is None:
                    continue
                pad = (f"{4 * offset}x " if offset else "") + f"{n}f"
                rest = floats - offset - n
                content.append((self.buffers[obj.id - 1],
                                pad + (f" {4 * rest}x" if rest else ""), name))
            self._vaos[key] = self.ctx.vertex_array(prog, content)
        return self._vaos[key]

    def pose(self, obj: SceneObject, t: float, t_open: float, t_close: float, times=None):
        """A skinned object's buffer posed for a draw at these times (kept while they
        hold); nothing for a rigid one."""
        if obj.skin is None:
            return
        key = obj.skin.stamp(t, t_open, t_close, *(times or ()))
        if self._posed.get(obj.id) != key:
            data = skinned_vertex_data(obj, t, t_open, t_close, times)
            self.buffers[obj.id - 1].write(data.tobytes())
            self._posed[obj.id] = key

    @staticmethod
    def bind_camera(prog: moderngl.Program, cam, t: float, size: tuple[int, int]):
        """The camera at the frame time (glsl/passes/motion.glsl; its views at shutter open and
        close reach the shaders through bind_object)."""
        set_uniform(prog, "u_view", cam.view(t))
        proj = cam.projection()
        set_uniform(prog, "u_proj", depth.projection(prog.ctx, proj, cam.spec.near,
                                                     cam.spec.far))
        set_uniform(prog, "u_focal", (float(proj[0, 0]), float(proj[1, 1])))
        set_uniform(prog, "u_viewport", tuple(float(x) for x in size))
        set_uniform(prog, "u_near", float(cam.spec.near))

    def light_defines(self) -> dict:
        """What glsl/passes/shading.glsl needs defined: this scene's lights, and the texture kinds'
        codes (TEX_CHECKER, ... as TEX_KINDS numbers them)."""
        return {"MAX_LIGHTS": max(self.max_lights, 1),
                "LIGHTS_TEXTURE": int(self.light_texture is not None),
                "LIGHTS_PER_ROW": LIGHTS_PER_ROW,
                **{f"TEX_{kind.upper()}": code for kind, code in TEX_KINDS.items() if kind}}

    def bind_lights(self, prog: moderngl.Program):
        s = self.scene
        set_uniform(prog, "u_ambient", s.ambient)
        set_uniform(prog, "u_num_lights", len(s.lights))
        if self.light_texture is not None:
            self.light_texture.use(LIGHT_UNIT)
            set_uniform(prog, "u_lights", LIGHT_UNIT)
            return
        dirs = np.zeros((self.max_lights, 3), np.float32)
        cols = np.zeros((self.max_lights, 3), np.float32)
        for k, light in enumerate(s.lights):
            dirs[k], cols[k] = light.direction, light.color
        if prog.get("u_light_dir", None) is not None:
            prog["u_light_dir"].write(dirs.tobytes())
            prog["u_light_color"].write(cols.tobytes())

    def bind_material(self, prog: moderngl.Program, obj: SceneObject,
                      material: Material | None = None):
        """`material` (one of the object's parts'), else the object's."""
        m = obj.material if material is None else material
        tex = m.texture
        set_uniform(prog, "u_albedo", m.albedo)
        set_uniform(prog, "u_specular", float(m.specular))
        set_uniform(prog, "u_shininess", float(m.shininess))
        set_uniform(prog, "u_tex_kind", TEX_KINDS[tex.kind if tex else None])
        if tex is not None:
            set_uniform(prog, "u_tex_size", float(tex.size))
            set_uniform(prog, "u_tex_axis", int(tex.axis))
            set_uniform(prog, "u_albedo2", tex.albedo2)
        if tex is not None and id(tex) in self.images:
            self.images[id(tex)].use(TEXTURE_UNIT_IMAGE)
            set_uniform(prog, "u_tex_image", TEXTURE_UNIT_IMAGE)

    @staticmethod
    def object_matrices(obj: SceneObject, cam, t: float, t_open: float, t_close: float,
                        memo: dict | None = None
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """T(-eye(t)) M(t) (world positions relative to the eye at t), V(t_open) M(t_open),
        V(t_close) M(t_close) (glsl/passes/motion.glsl) and the normal matrix of M(t): what
        bind_object sets and reveal_shade's object table holds, composed here in float64 so
        that the shaders' float32 never holds a world translation (a scene far from the
        origin keeps its detail). `memo`: a dict that lives one frame (camera and objects
        fixed), shared by the passes that ask for the same times (the hybrid's G-buffer
        and reveal_shade)."""
        key = (obj.id, t, t_open, t_close)
        mats = None if memo is None else memo.get(key)
        if mats is None:
            # The camera's eye and views at these times, asked once a frame, not per object.
            poses = None if memo is None else memo.get(("camera", t, t_open, t_close))
            if poses is None:
                poses = (cam.eye(t), cam.view(t_open), cam.view(t_close))
                if memo is not None:
                    memo[("camera", t, t_open, t_close)] = poses
            eye, view_open, view_close = poses
            model = obj.matrix(t)
            model.flags.writeable = False   # (a copy, kept read-only: shared below)
            if memo is not None:            # (M(t) itself: the reveal's poses, frame_models)
                memo[("model", obj.id, t)] = model
            model_eye = model.copy()
            model_eye[:3, 3] -= eye
            mats = (model_eye, view_open @ obj.matrix(t_open),
                    view_close @ obj.matrix(t_close), _normal_matrix(obj, model))
            if memo is not None:
                memo[key] = mats
        return mats

    @staticmethod
    def path_matrices(obj: SceneObject, cam, times, memo: dict | None = None) -> bytes:
        """V(t_k) M(t_k) for the path's times (glsl/passes/path.glsl), composed in float64, as
        the bytes of a GLSL mat4 array; `memo` as object_matrices'."""
        key = ("path", obj.id, tuple(times))
        out = None if memo is None else memo.get(key)
        if out is None:
            views = None if memo is None else memo.get(("path_views", tuple(times)))
            if views is None:
                views = [cam.view(tk) for tk in times]
                if memo is not None:
                    memo[("path_views", tuple(times))] = views
            out = b"".join(mat(v @ obj.matrix(tk)) for v, tk in zip(views, times))
            if memo is not None:
                memo[key] = out
        return out

    def bind_object(self, prog: moderngl.Program, obj: SceneObject, cam, t: float,
                    t_open: float, t_close: float, memo: dict | None = None):
        """Transforms of `obj` at the frame time, and seen by the camera `cam` at shutter
        open and close (glsl/passes/motion.glsl); `memo` as object_matrices'. Returns them."""
        model_eye, open_, close, normal = self.object_matrices(obj, cam, t, t_open, t_close,
                                                               memo)
        set_uniform(prog, "u_model_eye", model_eye)
        set_uniform(prog, "u_modelview_open", open_)
        set_uniform(prog, "u_modelview_close", close)
        set_uniform(prog, "u_normal_matrix", normal)
        set_uniform(prog, "u_object_id", obj.id)
        self.bind_material(prog, obj)
        return model_eye, open_, close, normal

    def release(self):
        for v in self._vaos.values():
            v.release()
        for b in {id(b): b for b in self.buffers}.values():
            b.release()
        for t in self.images.values():
            t.release()
        if self.light_texture is not None:
            self.light_texture.release()
        self._vaos.clear()
