"""The scene model: what a scene file describes, after loading and validation.

`world.loader.load_scene` builds these from TOML (docs/scene-format.md). Everything here
is plain numpy (float64) so the rasteriser, the ray tracer and the tests share one truth
for transforms and motion.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from world import conventions
from world.errors import UserError
from world import transforms as tf


@dataclass
class Texture:
    kind: str                         # "checker", "stripes" or "image"
    size: float = 1.0                 # checker / stripes cell size (mesh units)
    axis: int = 0                     # stripes: 0, 1 or 2
    albedo2: np.ndarray = field(default_factory=lambda: np.zeros(3))
    path: Path | None = None          # image
    image: np.ndarray | None = None   # image: linear RGB float32, (H, W, 3), top row first


@dataclass
class Material:
    albedo: np.ndarray = field(default_factory=lambda: np.full(3, 0.8))
    specular: float = 0.0
    shininess: float = 32.0
    texture: Texture | None = None


@dataclass
class Mesh:
    """A triangle mesh in its own (local) coordinates, as trimesh built it."""
    vertices: np.ndarray              # (n, 3) float64
    faces: np.ndarray                 # (m, 3) int64
    vertex_normals: np.ndarray        # (n, 3) float64, trimesh's
    face_normals: np.ndarray          # (m, 3) float64, trimesh's (winding)
    uv: np.ndarray | None = None      # (n, 2) float64, origin bottom-left, or None


def rotation_at(w, t: float) -> np.ndarray:
    """Rot(w * t) as a 3x3 matrix."""
    return tf.axis_angle(np.asarray(w, dtype=np.float64) * t)


# ---------------------------------------------------------------- keyframed motion (v1.1)

INTERPOLATIONS = ("linear", "smooth")


def key_segment(times: np.ndarray, t: float) -> tuple[int, float]:
    """(i, u): t clamped to [times[0], times[-1]], the segment i with times[i] <= t <=
    times[i+1] and u = (t - times[i]) / (times[i+1] - times[i]); (0, 0.0) for one key."""
    n = len(times)
    if n == 1:
        return 0, 0.0
    t = min(max(float(t), float(times[0])), float(times[-1]))
    i = min(int(np.searchsorted(times, t, side="right")) - 1, n - 2)
    return i, (t - float(times[i])) / (float(times[i + 1]) - float(times[i]))


def key_curve(values: np.ndarray, i: int, u: float, smooth: bool) -> np.ndarray:
    """Segment i of the keys' curve at u: linear P_i + u (P_(i+1) - P_i), or the uniform
    Catmull-Rom spline with the end keys repeated (P_(-1) = P_0, P_n = P_(n-1))."""
    n = len(values)
    if n == 1:
        return values[0].copy()
    p1, p2 = values[i], values[i + 1]
    if not smooth:
        return p1 + u * (p2 - p1)
    p0, p3 = values[max(i - 1, 0)], values[min(i + 2, n - 1)]
    return 0.5 * (2.0 * p1 + (p2 - p0) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u * u
                  + (3.0 * p1 - p0 - 3.0 * p2 + p3) * u * u * u)


def _frozen(*arrays) -> bytes:
    """Make the arrays read-only; their bytes together (a key's identity for the memos)."""
    for a in arrays:
        a.flags.writeable = False
    return b"".join(a.tobytes() for a in arrays)


@dataclass(frozen=True, eq=False)
class ObjectKeys:
    """An object's keyed pose: n keys at strictly increasing times (read-only arrays)."""
    times: np.ndarray                 # (n,) seconds
    positions: np.ndarray             # (n, 3)
    rotations: np.ndarray             # (n, 3) Euler degrees, R0 = Rz @ Ry @ Rx
    scales: np.ndarray                # (n, 3)
    interpolation: str = "linear"     # "linear" or "smooth" (positions and scales)

    def __post_init__(self):
        quats = np.array([tf.quat_euler_xyz_degrees(r) for r in self.rotations])
        object.__setattr__(self, "quats", quats)
        object.__setattr__(self, "token", _frozen(self.times, self.positions, self.rotations,
                                                  self.scales, quats)
                           + self.interpolation.encode())

    @property
    def varies(self) -> bool:
        """Whether the pose changes over time (some key differs from the first)."""
        return bool((self.positions != self.positions[0]).any()
                    or (self.rotations != self.rotations[0]).any()
                    or (self.scales != self.scales[0]).any())

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(position, unit quaternion, scale) at time t; rotations slerped in both modes."""
        i, u = key_segment(self.times, t)
        smooth = self.interpolation == "smooth"
        q = self.quats[0] if len(self.times) == 1 else tf.slerp(self.quats[i], self.quats[i + 1], u)
        return (key_curve(self.positions, i, u, smooth), q,
                key_curve(self.scales, i, u, smooth))

    def matrix(self, t: float) -> np.ndarray:
        """M(t) = T(p(t)) @ R(q(t)) @ S(s(t))."""
        return tf.trs(*self.pose(t))

    def retimed(self, t0: float, speed: float) -> "ObjectKeys":
        """The same path run `speed` times as fast about the time t0 (pose'(t) =
        pose(t0 + speed (t - t0))); speed 0 holds the pose of t0."""
        if speed == 0.0:
            p, q, s = self.pose(t0)
            euler = tf.euler_xyz_degrees_of(tf.quat_matrix(q))
            return ObjectKeys(np.array([float(t0)]), p[None], euler[None], s[None],
                              self.interpolation)
        times = t0 + (self.times - t0) / speed
        order = slice(None) if speed > 0 else slice(None, None, -1)
        return ObjectKeys(times[order].copy(), self.positions[order].copy(),
                          self.rotations[order].copy(), self.scales[order].copy(),
                          self.interpolation)

    def to_dicts(self) -> list[dict]:
        return [{"time": float(t), "position": p.tolist(), "rotation": r.tolist(),
                 "scale": s.tolist()}
                for t, p, r, s in zip(self.times, self.positions, self.rotations, self.scales)]


@dataclass(frozen=True, eq=False)
class CameraKeys:
    """The camera's keyed path: n keys at strictly increasing times (read-only arrays)."""
    times: np.ndarray                 # (n,) seconds
    positions: np.ndarray             # (n, 3) eye
    look_ats: np.ndarray              # (n, 3)
    ups: np.ndarray                   # (n, 3)
    interpolation: str = "linear"

    def __post_init__(self):
        object.__setattr__(self, "token", _frozen(self.times, self.positions, self.look_ats,
                                                  self.ups) + self.interpolation.encode())

    @property
    def varies(self) -> bool:
        return bool((self.positions != self.positions[0]).any()
                    or (self.look_ats != self.look_ats[0]).any()
                    or (self.ups != self.ups[0]).any())

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(eye, unit forward, up) at t: eye p(t), forward normalize(look_at(t) - p(t)),
        up(t) (made orthonormal with forward where the view is built, as for every camera)."""
        i, u = key_segment(self.times, t)
        smooth = self.interpolation == "smooth"
        eye = key_curve(self.positions, i, u, smooth)
        fwd = key_curve(self.look_ats, i, u, smooth) - eye
        n, up = np.linalg.norm(fwd), key_curve(self.ups, i, u, smooth)
        # Keys each with a view can pass through none (look_at crossing the eye, up
        # turning through the view): no limit exists there (the view flips), so a line.
        if not (0.0 < n < np.inf) or np.linalg.norm(np.cross(fwd / n, up)) <= 1e-9 * np.linalg.norm(up):
            raise UserError(f"camera.keys: at t = {t!r} s the keyed camera has no view "
                            "(look_at meets the eye, or up lies along the view): add a key "
                            "that keeps them apart")
        return eye, fwd / n, up

    def to_dicts(self) -> list[dict]:
        return [{"time": float(t), "position": p.tolist(), "look_at": a.tolist(),
                 "up": u.tolist()}
                for t, p, a, u in zip(self.times, self.positions, self.look_ats, self.ups)]


@dataclass(kw_only=True, eq=False)
class Placement:
    """A node's own motion (pose and velocities, or keys) under an optional parent:
    M(t) = M_parent(t) @ M_own(t) (scene format v1.2, "Parents"). Plain objects are
    placements with a mesh; a glTF entry's root is one without."""
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.zeros(3))   # Euler degrees
    scale: np.ndarray = field(default_factory=lambda: np.ones(3))
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    # Keyed motion instead of the pose and velocities above (which then hold the first
    # key's pose and zero velocities, for what reads a rest pose).
    keys: ObjectKeys | None = None
    # What this node hangs from: another placement or a glTF node (AssetNode); None: the world.
    parent: "Placement | AssetNode | None" = None
    # Kept own matrices (the last 8, by t and every field they depend on), and R0 @ S by
    # the rotation and scale it was made from.
    _matrix_memo: dict = field(default_factory=dict, init=False, repr=False)
    _rest_cache: tuple | None = field(default=None, init=False, repr=False)

    @property
    def own_moving(self) -> bool:
        if self.keys is not None:
            return self.keys.varies
        return bool(self.velocity.any() or self.angular_velocity.any())

    @property
    def moving(self) -> bool:
        """Whether M(t) changes with t: its own motion or anything above it moves."""
        return self.own_moving or (self.parent is not None and self.parent.moving)

    def matrix(self, t: float) -> np.ndarray:
        """M(t) = M_parent(t) @ M_own(t) (a new array)."""
        own = self.own_matrix(t)
        return own if self.parent is None else self.parent.matrix(t) @ own

    def own_matrix(self, t: float) -> np.ndarray:
        """M_own(t) = T(position + velocity t) @ Rot(angular_velocity t) @ R0 @ S, or for a
        keyed node T(p(t)) @ R(q(t)) @ S(s(t)).

        A frame asks for the same few times (t, shutter open and close) in many passes:
        the last few results are kept, keyed by t and every field they depend on. A node
        that does not move has one matrix at every t (translation p + 0 t = p, no
        turn): keyed as t = 0, so an animation's frames do not rebuild it three times
        each."""
        moving = self.own_moving
        if self.keys is not None:
            key = (float(t) if moving else 0.0, self.keys.token)
        else:
            key = (float(t) if moving else 0.0, self.position.tobytes(), self.velocity.tobytes(),
                   self.angular_velocity.tobytes(), self.rotation.tobytes(),
                   self.scale.tobytes())
        memo = self._matrix_memo
        m = memo.get(key)
        if m is None and self.keys is not None:
            m = self.keys.matrix(t if moving else float(self.keys.times[0]))
            if len(memo) >= 8:
                memo.pop(next(iter(memo)))
            memo[key] = m
        elif m is None:
            # T(p) @ rest, written at once: rest's last column is (0, 0, 0, 1), so the
            # product's is p and its 3x3 rest's (a product by 1 and sums of zeros).
            m = self._rest()
            m[:3, 3] = self.position + (self.velocity * t if moving else 0.0)
            if moving and self.angular_velocity.any():
                m[:3, :3] = rotation_at(self.angular_velocity, t) @ m[:3, :3]
            if len(memo) >= 8:
                memo.pop(next(iter(memo)))
            memo[key] = m
        return m.copy()

    def own_matrices(self, times) -> np.ndarray:
        """own_matrix at each of `times`: (n, 4, 4), a turn's rotations made at once."""
        times = np.asarray(times, np.float64)
        if self.keys is not None or not self.own_moving:
            return np.stack([self.own_matrix(t) for t in times])
        m = np.repeat(self._rest()[None], len(times), axis=0)
        m[:, :3, 3] = self.position + self.velocity * times[:, None]
        if self.angular_velocity.any():
            turns = tf.axis_angles(self.angular_velocity[None] * times[:, None])
            m[:, :3, :3] = turns @ m[:, :3, :3]
        return m

    def _rest(self) -> np.ndarray:
        """R0 @ S, cached against the values it was made from (the fields may be edited)."""
        key = (self.rotation.tobytes(), self.scale.tobytes())
        if self._rest_cache is None or self._rest_cache[0] != key:
            self._rest_cache = (key, tf.homogeneous(tf.euler_xyz_degrees(self.rotation))
                                @ tf.scale(self.scale))
        return self._rest_cache[1].copy()


@dataclass(eq=False)
class SceneObject(Placement):
    """A drawn object: a mesh with one id, placed like any node. A glTF mesh node is one
    whose parent is its AssetNode (own pose the identity); a skinned one hangs from its
    entry's root and deforms its mesh by `skin` (scene format v1.2)."""
    name: str
    id: int                           # 1, 2, 3 ... in file order; 0 is the background
    mesh: Mesh
    material: Material
    shading: str = "smooth"           # "smooth" or "flat"
    # Linear blend skinning of the mesh (world.skinning.Skin), or None: a rigid mesh.
    skin: object | None = None
    # A mesh of several materials (glTF primitives): (first face, face count, material)
    # per part, covering the faces in order; None: `material` for every face.
    parts: list | None = None
    # world.path_bend's sample of a rigid mesh's vertices: (the mesh, homogeneous points).
    bend_points: tuple | None = field(default=None, init=False, repr=False)

    @property
    def moving(self) -> bool:
        return (self.own_moving or (self.parent is not None and self.parent.moving)
                or (self.skin is not None and self.skin.moving))

    def vertices_at(self, t: float) -> np.ndarray:
        """The mesh's vertices in the object's own space at time t (what M(t) places): a
        skinned mesh's posed at t, else the mesh's own."""
        return self.mesh.vertices if self.skin is None else self.skin.deformed(t)[0]


@dataclass
class CameraSpec:
    position: np.ndarray
    look_at: np.ndarray
    fov_y: float
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    near: float = 0.05
    far: float = 100.0
    shutter: float = 0.0
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    # A keyed path instead of position, look_at and the velocities (which then hold the
    # first key's pose and zero velocities; `up` is the keys' default up).
    keys: CameraKeys | None = None
    # Kept poses: the last 8, by t and every field they depend on.
    _pose_memo: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def moving(self) -> bool:
        if self.keys is not None:
            return self.keys.varies
        return bool(self.velocity.any() or self.angular_velocity.any())

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(eye, forward, up) at time t; forward and up are turned by Rot(angular_velocity t),
        or for a keyed camera CameraKeys.pose(t).

        Read-only arrays, the last few kept by t and every field they depend on: a frame
        asks for a handful of times in many places."""
        if self.keys is not None:
            key = (float(t), self.keys.token)
        else:
            key = (float(t), self.position.tobytes(), self.look_at.tobytes(), self.up.tobytes(),
                   self.velocity.tobytes(), self.angular_velocity.tobytes())
        memo = self._pose_memo
        pose = memo.get(key)
        if pose is None and self.keys is not None:
            pose = tuple(np.array(a) for a in self.keys.pose(t))
            for a in pose:
                a.flags.writeable = False
            if len(memo) >= 8:
                memo.pop(next(iter(memo)))
            memo[key] = pose
        elif pose is None:
            r = rotation_at(self.angular_velocity, t)
            eye = self.position + self.velocity * t
            fwd = r @ (self.look_at - self.position)
            pose = (eye, fwd / np.linalg.norm(fwd), r @ self.up)
            for a in pose:
                a.flags.writeable = False
            if len(memo) >= 8:
                memo.pop(next(iter(memo)))
            memo[key] = pose
        return pose

    def detach(self, t: float):
        """Leave the keys for a still camera at the pose of time t (the viewer's mouse and
        keyboard moves start from what is shown); the look-at point keeps its distance."""
        if self.keys is None:
            return
        eye, fwd, up = self.keys.pose(t)
        i, u = key_segment(self.keys.times, t)
        look = key_curve(self.keys.look_ats, i, u, self.keys.interpolation == "smooth")
        self.position = eye.copy()
        self.look_at = eye + fwd * float(np.linalg.norm(look - eye))
        self.up = up.copy()
        self.velocity, self.angular_velocity = np.zeros(3), np.zeros(3)
        self.keys = None

    def to_dict(self) -> dict:
        """The camera as a scene file's [camera] table (JSON types): what an image's sidecar
        records, read back by world.loader.check_camera."""
        d = {"fov_y": self.fov_y, "up": self.up.tolist(), "near": self.near, "far": self.far,
             "shutter": self.shutter}
        if self.keys is not None:
            d.update(interpolation=self.keys.interpolation, keys=self.keys.to_dicts())
        else:
            d.update(position=self.position.tolist(), look_at=self.look_at.tolist(),
                     velocity=self.velocity.tolist(),
                     angular_velocity=self.angular_velocity.tolist())
        return d


@dataclass
class Light:
    direction: np.ndarray             # the direction the light travels, unit length
    color: np.ndarray = field(default_factory=lambda: np.ones(3))


@dataclass
class RenderDefaults:
    width: int = 1280
    height: int = 720
    time: float = 0.0


@dataclass
class Scene:
    name: str
    path: Path | None
    camera: CameraSpec
    background: np.ndarray = field(default_factory=lambda: np.zeros(3))
    ambient: np.ndarray = field(default_factory=lambda: np.zeros(3))
    render: RenderDefaults = field(default_factory=RenderDefaults)
    lights: list[Light] = field(default_factory=list)
    objects: list[SceneObject] = field(default_factory=list)
    # The glTF entries (world.gltf_scene.AssetInstance), for what lists their animations.
    assets: list = field(default_factory=list)

    def exposure(self, t: float) -> tuple[float, float]:
        """[t - shutter/2, t + shutter/2] of the camera's shutter (conventions.exposure)."""
        return conventions.exposure(t, self.camera.shutter)

    def sample_times(self, t: float, n: int) -> np.ndarray:
        """n stratified times over the camera's exposure (conventions.sample_times)."""
        return conventions.sample_times(t, self.camera.shutter, n)

    def pose(self, times) -> int:
        """Every glTF entry's node matrices and every skinned mesh's vertices at `times`,
        evaluated now (kept: the passes that read them find them); returns the skinned
        vertices posed."""
        posed = 0
        for t in times:
            for instance in self.assets:
                if instance.animated:
                    instance.worlds(float(t))
            for o in self.objects:
                if o.skin is not None:
                    o.skin.deformed(float(t))
                    posed += len(o.mesh.vertices)
        return posed
