"""A loaded glTF asset as plain numpy arrays: node tree, triangle primitives, base-colour
materials, skins and animations, and which animations an entry plays and when.

Conventions: matrices are column-vector (p' = M @ p; glTF stores them column-major);
quaternions are (w, x, y, z), world/transforms.py's order. Arrays are read-only where
several items may share them.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from world.gltf.curves import GltfSampler
from world.gltf.document import GltfError


@dataclass
class GltfMaterial:
    base_color: np.ndarray          # (4,) float64 baseColorFactor
    image: np.ndarray | None        # (H, W, 3) float32 linear rgb, top row first
    name: str


@dataclass
class GltfPart:
    """One triangle primitive. Its arrays are read-only (several primitives may share an
    accessor's decoded array): copy before modifying."""
    positions: np.ndarray           # (n, 3) float64
    normals: np.ndarray | None      # (n, 3) float64
    uv: np.ndarray | None           # (n, 2) float64, (0, 0) = top-left of the image
    faces: np.ndarray               # (m, 3) int64
    joints: np.ndarray | None       # (n, 4 or 8) int64
    weights: np.ndarray | None      # (n, 4 or 8) float64
    material: int | None


@dataclass
class GltfNode:
    index: int
    name: str
    parent: int | None
    children: list[int]
    matrix: np.ndarray | None       # (4, 4) column-vector convention
    translation: np.ndarray         # (3,)
    rotation: np.ndarray            # (4,) w, x, y, z (normalised)
    scale: np.ndarray               # (3,)
    mesh: int | None
    skin: int | None


@dataclass
class GltfSkin:
    joints: list[int]
    inverse_bind: np.ndarray        # (J, 4, 4)


@dataclass
class GltfChannel:
    node: int
    path: str
    sampler: GltfSampler


@dataclass
class GltfAnimation:
    name: str
    channels: list[GltfChannel]
    # [first, last] key time over every sampler of the animation (weights channels' and
    # unused samplers' too: "the key times of every sampler"); None without samplers.
    time_span: tuple[float, float] | None = None


def walk(nodes: list[GltfNode], starts) -> list[int]:
    """The nodes below `starts` (indices into `nodes`), pre-order: children in array order."""
    out: list[int] = []
    stack = list(reversed(starts))
    while stack:
        i = stack.pop()
        out.append(i)
        stack.extend(reversed(nodes[i].children))
    return out


class GltfAsset:
    """A loaded asset (world.gltf.load_gltf). Node lists are indexed by glTF node index."""

    def __init__(self, path: Path, nodes, meshes, materials, skins, animations, roots, ignored):
        self.path = Path(path)
        self.nodes: list[GltfNode] = nodes
        self.meshes: list[list[GltfPart]] = meshes
        self.materials: list[GltfMaterial] = materials
        self.skins: list[GltfSkin] = skins
        self.animations: list[GltfAnimation] = animations
        self.roots: list[int] = roots
        self.ignored: list[str] = ignored

    # -- structure

    def walk(self, starts) -> list[int]:
        """The nodes below `starts`, pre-order: children in array order."""
        return walk(self.nodes, starts)

    def depth_first(self) -> list[int]:
        """The scene's nodes, pre-order: roots in array order, children in array order."""
        return self.walk(self.roots)

    def mesh_nodes(self) -> list[int]:
        """depth_first() filtered to the nodes with a mesh: the objects, in id order."""
        return [i for i in self.depth_first() if self.nodes[i].mesh is not None]

    # -- animations

    def select(self, animation="all") -> tuple[int, ...]:
        """Indices of the animations played: "all", "none", a name or an index."""
        if isinstance(animation, str):
            if animation == "all":
                return tuple(range(len(self.animations)))
            if animation == "none":
                return ()
            for i, an in enumerate(self.animations):
                if an.name == animation:
                    return (i,)
            raise GltfError(f"no animation named {animation!r}; {self._available()}")
        if isinstance(animation, (int, np.integer)) and not isinstance(animation, bool):
            if 0 <= int(animation) < len(self.animations):
                return (int(animation),)
            raise GltfError(f"animation index {int(animation)} out of range; {self._available()}")
        raise GltfError(f"animation must be a name, an index, \"all\" or \"none\", not {animation!r}")

    def _available(self) -> str:
        if not self.animations:
            return "the asset has no animations"
        names = ", ".join(f"{i}: {an.name!r}" for i, an in enumerate(self.animations))
        return f"available: {names}"

    def time_range(self, anims) -> tuple[float, float]:
        spans = [self.animations[i].time_span for i in anims]
        spans = [s for s in spans if s is not None]
        if not spans:
            return (0.0, 0.0)
        return (min(s[0] for s in spans), max(s[1] for s in spans))

    def animation_time(self, t, anims, time_offset=0.0, time_scale=1.0, loop=False) -> float:
        """a = (t - time_offset) * time_scale, then with `loop` A0 + mod(a - A0, A1 - A0)."""
        a = (float(t) - float(time_offset)) * float(time_scale)
        if loop:
            a0, a1 = self.time_range(anims)
            if a1 > a0:
                a = a0 + (a - a0) % (a1 - a0)
        return a
