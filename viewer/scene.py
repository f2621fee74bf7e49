"""The scene model: what a scene file describes, after loading and validation.

`viewer.scene_loader.load_scene` builds these from TOML (SCENE_FORMAT.md). Everything here
is plain numpy (float64) so the rasteriser, the ray tracer and the tests share one truth
for transforms and motion.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import conventions
from . import transforms as tf


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


@dataclass
class SceneObject:
    name: str
    id: int                           # 1, 2, 3 ... in file order; 0 is the background
    mesh: Mesh
    material: Material
    shading: str = "smooth"           # "smooth" or "flat"
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.zeros(3))   # Euler degrees
    scale: np.ndarray = field(default_factory=lambda: np.ones(3))
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def moving(self) -> bool:
        return bool(self.velocity.any() or self.angular_velocity.any())   # (np.any: 3x slower)

    def matrix(self, t: float) -> np.ndarray:
        """M(t) = T(position + velocity t) @ Rot(angular_velocity t) @ R0 @ S.

        A frame asks for the same few times (t, shutter open and close) in many passes:
        the last few results are kept, keyed by t and every field they depend on. An
        object that does not move has one matrix at every t (translation p + 0 t = p, no
        turn): keyed as t = 0, so an animation's frames do not rebuild it three times
        each (living_room: 28 still objects)."""
        moving = self.moving
        key = (float(t) if moving else 0.0, self.position.tobytes(), self.velocity.tobytes(),
               self.angular_velocity.tobytes(), self.rotation.tobytes(), self.scale.tobytes())
        memo = self.__dict__.setdefault("_matrix_memo", {})
        m = memo.get(key)
        if m is None:
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

    def _rest(self) -> np.ndarray:
        """R0 @ S, cached against the values it was made from (the fields may be edited)."""
        key = (self.rotation.tobytes(), self.scale.tobytes())
        cached = getattr(self, "_rest_cache", None)
        if cached is None or cached[0] != key:
            cached = (key, tf.homogeneous(tf.euler_xyz_degrees(self.rotation)) @ tf.scale(self.scale))
            self._rest_cache = cached
        return cached[1].copy()


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

    @property
    def moving(self) -> bool:
        return bool(self.velocity.any() or self.angular_velocity.any())   # (np.any: 3x slower)

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(eye, forward, up) at time t; forward and up are turned by Rot(angular_velocity t).

        Read-only arrays, the last few kept by t and every field they depend on: a frame
        asks for a handful of times in many places (a turning camera's pose costs ~20 us)."""
        key = (float(t), self.position.tobytes(), self.look_at.tobytes(), self.up.tobytes(),
               self.velocity.tobytes(), self.angular_velocity.tobytes())
        memo = self.__dict__.setdefault("_pose_memo", {})
        pose = memo.get(key)
        if pose is None:
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

    def exposure(self, t: float) -> tuple[float, float]:
        """[t - shutter/2, t + shutter/2] of the camera's shutter (conventions.exposure)."""
        return conventions.exposure(t, self.camera.shutter)

    def sample_times(self, t: float, n: int) -> np.ndarray:
        """n stratified times over the camera's exposure (conventions.sample_times)."""
        return conventions.sample_times(t, self.camera.shutter, n)
