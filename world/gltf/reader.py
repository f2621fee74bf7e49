"""glTF 2.0 assets (scene format v1.2): node trees, triangle meshes, base-colour materials,
skins and TRS animations, read into plain numpy arrays.

No GL, no trimesh: `load_gltf` reads a `.gltf` (embedded or external buffers and images)
or a `.glb`, checks everything the format relies on once, and raises nothing but
GltfError (one line naming the asset item, e.g. `accessors[3]: ...`; the scene loader
prefixes file and entry). After a successful load, evaluation (`sample`,
`GltfAsset.local_matrices` / `world_matrices` / `joint_matrices`, `skin_vertices`) never
raises for the asset's own data.

The JSON is parsed with the standard library (strict: NaN/Infinity literals refused) and
the GLB container is read here as well, so that every malformation gets its own message;
pygltflib supplies the glTF constants. Accessors are decoded as glTF 2.0 says: byteStride,
matrix column padding, normalized integer components, sparse substitution.

Conventions: matrices are column-vector (p' = M @ p; glTF stores them column-major);
quaternions are in glTF's (x, y, z, w) order throughout this module. Decoded arrays are
read-only and may be shared between primitives (copy before modifying).

What the scene loader does with it (SCENE_FORMAT.md, v1.2): one object per
`mesh_nodes()` entry, in that order; M(t) = P(t) @ world_matrices(a)[node], with
a = animation_time(t, ...); a skinned node draws skin_vertices(...) with
joint_matrices(skin, worlds) and P(t) only (its own World is not applied), and moves when
`skin_moving(skin, anims)`; `ignored` is printed once.

Sizes are bounded before anything is allocated (MAX_* below), so that a small hostile file
cannot make the program allocate gigabytes: file sizes, decoded accessor components,
vertices and triangles of the drawn scene, nodes, joints, image pixels.
"""
from __future__ import annotations

import base64
import binascii
import io
import json
import math
import os
import stat
import struct
import urllib.parse
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pygltflib as G

MAX_ASSET_BYTES = 256 * 2**20         # any one .gltf/.glb/.bin/image file or data URI
MAX_ACCESSOR_COMPONENTS = 2**26        # all decoded accessor components together (512 MiB as float64)
MAX_VERTICES = 2**24                   # vertices of all mesh-node instances of the scene
MAX_TRIANGLES = 2**24                  # triangles of all mesh-node instances of the scene
MAX_NODES = 2**16
MAX_JOINTS = 2**16                     # per skin
MAX_ITEMS = 2**16                      # entries of any top-level array (meshes, accessors, ...)
MAX_IMAGE_PIXELS = 2**24               # per image, checked from its header before decoding
MAX_TOTAL_IMAGE_PIXELS = 2**26
MAX_JSON_DEPTH = 64

INTERPOLATIONS = ("STEP", "LINEAR", "CUBICSPLINE")
TRS_PATHS = ("translation", "rotation", "scale")
SLERP_MIN_ANGLE = 1e-6

# Required extensions this reader can honour by ignoring them (the format ignores what they
# add: material models, lights, texture transforms) or by decoding them (quantized
# attributes are ordinary normalized/integer accessors here).
_TOLERATED_REQUIRED = ("KHR_mesh_quantization", "KHR_lights_punctual", "KHR_texture_transform",
                       "KHR_materials_variants", "KHR_xmp_json_ld")

_COMPONENT = {                         # componentType -> little-endian numpy dtype
    G.BYTE: np.dtype("<i1"), G.UNSIGNED_BYTE: np.dtype("<u1"),
    G.SHORT: np.dtype("<i2"), G.UNSIGNED_SHORT: np.dtype("<u2"),
    G.UNSIGNED_INT: np.dtype("<u4"), G.FLOAT: np.dtype("<f4"),
}
_TYPE = {"SCALAR": (1, 0), "VEC2": (2, 0), "VEC3": (3, 0), "VEC4": (4, 0),
         "MAT2": (4, 2), "MAT3": (9, 3), "MAT4": (16, 4)}     # -> (components, matrix rows)
_NORM_DIVISOR = {G.BYTE: 127.0, G.UNSIGNED_BYTE: 255.0, G.SHORT: 32767.0,
                 G.UNSIGNED_SHORT: 65535.0}
_FLOATISH = (G.FLOAT, G.BYTE, G.UNSIGNED_BYTE, G.SHORT, G.UNSIGNED_SHORT)   # float or normalized

_GLB_MAGIC = 0x46546C67               # b"glTF"
_CHUNK_JSON = 0x4E4F534A
_CHUNK_BIN = 0x004E4942


class GltfError(Exception):
    """One line saying what is wrong with the asset, naming the item (no file prefix).
    Line breaks that come with names or paths from the asset are escaped."""

    def __init__(self, message: str = ""):
        super().__init__(str(message).replace("\r", "\\r").replace("\n", "\\n"))


# ---------------------------------------------------------------- data classes

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
    rotation: np.ndarray            # (4,) x, y, z, w (normalised)
    scale: np.ndarray               # (3,)
    mesh: int | None
    skin: int | None


@dataclass
class GltfSkin:
    joints: list[int]
    inverse_bind: np.ndarray        # (J, 4, 4)


@dataclass
class GltfSampler:
    times: np.ndarray               # (n,) float64, strictly increasing, finite
    values: np.ndarray              # (n, c) or (n, 3, c) for CUBICSPLINE
    interpolation: str


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


# ---------------------------------------------------------------- evaluation

def _normalised(q: np.ndarray) -> np.ndarray:
    n = float(np.sqrt(q @ q))
    if n == 0.0 or not math.isfinite(n):
        return np.array([0.0, 0.0, 0.0, 1.0])
    return q / n


def slerp_xyzw(q0: np.ndarray, q1: np.ndarray, u: float) -> np.ndarray:
    """Shortest-arc slerp of the format (keys normalised first, dot product in float64,
    the second negated where it is < 0, normalised lerp below SLERP_MIN_ANGLE)."""
    q0 = _normalised(np.asarray(q0, dtype=np.float64))
    q1 = _normalised(np.asarray(q1, dtype=np.float64))
    d = float(q0[0] * q1[0] + q0[1] * q1[1] + q0[2] * q1[2] + q0[3] * q1[3])
    if d < 0.0:
        q1, d = -q1, -d
    theta = math.acos(min(d, 1.0))
    if theta < SLERP_MIN_ANGLE:
        return _normalised(q0 + u * (q1 - q0))
    s = math.sin(theta)
    return (math.sin((1.0 - u) * theta) * q0 + math.sin(u * theta) * q1) / s


def sample(sampler: GltfSampler, a: float, path: str) -> np.ndarray:
    """The channel value at animation time `a` (SCENE_FORMAT.md, glTF scenes): `a` clamped
    to the key range, segment i with k_i <= a < k_(i+1) (the last one at a = k_(n-1)),
    STEP / LINEAR (rotations: shortest-arc slerp) / CUBICSPLINE (Hermite; rotations
    normalised). Rotations are (x, y, z, w)."""
    k = sampler.times
    vals = sampler.values
    cubic = sampler.interpolation == "CUBICSPLINE"
    n = k.shape[0]
    rot = path == "rotation"
    if n == 1:
        v = (vals[0, 1] if cubic else vals[0]).astype(np.float64)
        return _normalised(v) if rot else v.copy()
    a = float(a)
    if not (a >= k[0]):                     # also NaN -> first key
        a = float(k[0])
    elif a > k[-1]:
        a = float(k[-1])
    i = int(np.searchsorted(k, a, side="right")) - 1
    i = min(max(i, 0), n - 2)
    k0, k1 = float(k[i]), float(k[i + 1])
    u = (a - k0) / (k1 - k0)
    interp = sampler.interpolation
    if interp == "STEP":
        v = vals[i + 1] if a >= k[-1] else vals[i]
        v = np.array(v, dtype=np.float64)
        return _normalised(v) if rot else v
    if interp == "LINEAR":
        if rot:
            return slerp_xyzw(vals[i], vals[i + 1], u)
        v0, v1 = vals[i].astype(np.float64), vals[i + 1].astype(np.float64)
        return v0 + u * (v1 - v0)
    # CUBICSPLINE: values[:, 0] in-tangent A, [:, 1] value V, [:, 2] out-tangent B
    d = k1 - k0
    u2, u3 = u * u, u * u * u
    v = ((2 * u3 - 3 * u2 + 1) * vals[i, 1] + d * (u3 - 2 * u2 + u) * vals[i, 2]
         + (-2 * u3 + 3 * u2) * vals[i + 1, 1] + d * (u3 - u2) * vals[i + 1, 0])
    v = np.asarray(v, dtype=np.float64)
    return _normalised(v) if rot else v


def quat_matrices(q: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations of (N, 4) quaternions (x, y, z, w), each normalised first."""
    q = np.asarray(q, dtype=np.float64)
    n = np.sqrt(np.einsum("ij,ij->i", q, q))
    bad = ~(n > 0) | ~np.isfinite(n)
    q = np.where(bad[:, None], [0.0, 0.0, 0.0, 1.0], q / np.where(bad, 1.0, n)[:, None])
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    r = np.empty((q.shape[0], 3, 3))
    r[:, 0, 0] = 1 - 2 * (y * y + z * z)
    r[:, 0, 1] = 2 * (x * y - w * z)
    r[:, 0, 2] = 2 * (x * z + w * y)
    r[:, 1, 0] = 2 * (x * y + w * z)
    r[:, 1, 1] = 1 - 2 * (x * x + z * z)
    r[:, 1, 2] = 2 * (y * z - w * x)
    r[:, 2, 0] = 2 * (x * z - w * y)
    r[:, 2, 1] = 2 * (y * z + w * x)
    r[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def trs_matrices(t: np.ndarray, q: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(N, 4, 4) T(t) @ R(q) @ S(s)."""
    m = np.zeros((t.shape[0], 4, 4))
    m[:, :3, :3] = quat_matrices(q) * s[:, None, :]
    m[:, :3, 3] = t
    m[:, 3, 3] = 1.0
    return m


def skin_vertices(positions, normals, joints, weights, joint_mats, normalize_normals=True):
    """Linear blend skinning: B = sum_i w_i J[j_i] (weights divided by their sum where it is
    not 1), positions -> B v, normals -> inverse transpose of B's 3x3 (computed as the
    cofactor matrix times sign(det), so a singular B never raises), normalised unless
    `normalize_normals` is False (then scaled as the true inverse transpose where det != 0).
    Zero-weight influences are ignored whatever their joint index. float64, vectorised."""
    p = np.asarray(positions, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    jm = np.asarray(joint_mats, dtype=np.float64)
    total = w.sum(axis=1)
    fix = (total != 1.0) & (total != 0.0)
    if fix.any():
        w = w / np.where(fix, total, 1.0)[:, None]
    j = np.where(w != 0.0, np.asarray(joints), 0)
    np.clip(j, 0, jm.shape[0] - 1, out=j)
    rows = jm[:, :3, :].reshape(jm.shape[0], 12)          # the 3x4 top of each joint matrix
    b = np.einsum("nk,nkc->nc", w, np.take(rows, j, axis=0))   # (n, 12): B row-major
    m = np.ascontiguousarray(b.T)                        # m[4 r + c] = B[r, c], each (n,)
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    out_p = np.empty((p.shape[0], 3))
    for r in range(3):
        out_p[:, r] = m[4 * r] * x + m[4 * r + 1] * y + m[4 * r + 2] * z + m[4 * r + 3]
    if normals is None:
        return out_p, None
    nrm = np.asarray(normals, dtype=np.float64)
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = (m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10])
    # cofactor matrix C = det * inverse transpose: C[r, c] = (-1)^(r+c) minor(r, c)
    c00, c01, c02 = a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20
    c10, c11, c12 = a02 * a21 - a01 * a22, a00 * a22 - a02 * a20, a01 * a20 - a00 * a21
    c20, c21, c22 = a01 * a12 - a02 * a11, a02 * a10 - a00 * a12, a00 * a11 - a01 * a10
    det = a00 * c00 + a01 * c01 + a02 * c02
    nx, ny, nz = nrm[:, 0], nrm[:, 1], nrm[:, 2]
    out_n = np.empty((nrm.shape[0], 3))
    out_n[:, 0] = c00 * nx + c01 * ny + c02 * nz
    out_n[:, 1] = c10 * nx + c11 * ny + c12 * nz
    out_n[:, 2] = c20 * nx + c21 * ny + c22 * nz
    if normalize_normals:
        length = np.sqrt(np.einsum("ni,ni->n", out_n, out_n))
        out_n /= np.where(length > 0.0, np.where(det < 0.0, -length, length), 1.0)[:, None]
    else:
        out_n /= np.where(det != 0.0, det, 1.0)[:, None]
    return out_p, out_n


# ---------------------------------------------------------------- the asset

class GltfAsset:
    """A loaded asset (see load_gltf). Node arrays are indexed by glTF node index."""

    def __init__(self, path: Path, nodes, meshes, materials, skins, animations, roots, ignored):
        self.path = Path(path)
        self.nodes: list[GltfNode] = nodes
        self.meshes: list[list[GltfPart]] = meshes
        self.materials: list[GltfMaterial] = materials
        self.skins: list[GltfSkin] = skins
        self.animations: list[GltfAnimation] = animations
        self.roots: list[int] = roots
        self.ignored: list[str] = ignored
        n = len(nodes)
        self._parent = np.array([-1 if nd.parent is None else nd.parent for nd in nodes], dtype=np.int64)
        self._has_matrix = np.array([nd.matrix is not None for nd in nodes], dtype=bool)
        self._t0 = np.array([nd.translation for nd in nodes], dtype=np.float64).reshape(n, 3)
        self._r0 = np.array([nd.rotation for nd in nodes], dtype=np.float64).reshape(n, 4)
        self._s0 = np.array([nd.scale for nd in nodes], dtype=np.float64).reshape(n, 3)
        self._m0 = np.array([np.eye(4) if nd.matrix is None else nd.matrix for nd in nodes],
                            dtype=np.float64).reshape(n, 4, 4)
        # nodes grouped by depth (all nodes, in or out of the scene): parents before children
        depth = np.zeros(n, dtype=np.int64)
        for i in self._all_depth_first():
            p = nodes[i].parent
            depth[i] = 0 if p is None else depth[p] + 1
        self._levels = [np.nonzero(depth == d)[0] for d in range(int(depth.max()) + 1)] if n else []
        self._cache: OrderedDict = OrderedDict()

    # -- structure

    def _walk(self, starts) -> list[int]:
        out: list[int] = []
        stack = list(reversed(starts))
        while stack:
            i = stack.pop()
            out.append(i)
            stack.extend(reversed(self.nodes[i].children))
        return out

    def _all_depth_first(self) -> list[int]:
        return self._walk([nd.index for nd in self.nodes if nd.parent is None])

    def depth_first(self) -> list[int]:
        """The scene's nodes, pre-order: roots in array order, children in array order."""
        return self._walk(self.roots)

    def mesh_nodes(self) -> list[int]:
        """depth_first() filtered to the nodes with a mesh: the objects, in id order."""
        return [i for i in self.depth_first() if self.nodes[i].mesh is not None]

    def node_name(self, i: int) -> str:
        return self.nodes[i].name

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

    def _channels(self, anims):
        """(node, path, sampler) of the played TRS channels in file order, `matrix` nodes left out."""
        for i in sorted(set(int(x) for x in anims)):
            for ch in self.animations[i].channels:
                if not self._has_matrix[ch.node]:
                    yield ch

    def animated(self, anims) -> np.ndarray:
        out = np.zeros(len(self.nodes), dtype=bool)
        for ch in self._channels(anims):
            out[ch.node] = True
        return out

    def moving(self, anims) -> np.ndarray:
        """animated(anims) or any ancestor animated."""
        out = self.animated(anims)
        for level in self._levels[1:]:
            out[level] |= out[self._parent[level]]
        return out

    def skin_moving(self, skin: int, anims) -> bool:
        """Whether a mesh skinned by `skin` moves: a joint or an ancestor of one animated."""
        mv = self.moving(anims)
        return bool(mv[self.skins[skin].joints].any())

    def local_matrices(self, a, anims) -> np.ndarray:
        """(N, 4, 4) local matrices at animation time `a` (already wrapped and scaled)."""
        t, r, s = self._t0.copy(), self._r0.copy(), self._s0.copy()
        for ch in self._channels(anims):           # file order: the later channel wins
            v = sample(ch.sampler, a, ch.path)
            if ch.path == "translation":
                t[ch.node] = v
            elif ch.path == "rotation":
                r[ch.node] = v
            else:
                s[ch.node] = v
        m = trs_matrices(t, r, s)
        m[self._has_matrix] = self._m0[self._has_matrix]
        return m

    def world_matrices(self, a, anims) -> np.ndarray:
        """(N, 4, 4) World(node) = World(parent) @ Local(node) at animation time `a`; the last
        few results are memoised (read-only arrays)."""
        key = (float(a), tuple(sorted(set(int(x) for x in anims))))
        hit = self._cache.get(key)
        if hit is not None:
            self._cache.move_to_end(key)
            return hit
        w = self.local_matrices(a, anims)
        for level in self._levels[1:]:
            w[level] = np.matmul(w[self._parent[level]], w[level])
        w.flags.writeable = False
        self._cache[key] = w
        while len(self._cache) > 8:
            self._cache.popitem(last=False)
        return w

    def joint_matrices(self, skin: int, worlds) -> np.ndarray:
        """(J, 4, 4) World(joint_j) @ inverseBind_j."""
        sk = self.skins[skin]
        return np.matmul(np.asarray(worlds)[sk.joints], sk.inverse_bind)

    def validate_skin(self, part: GltfPart, skin: int, where: str = "") -> None:
        """GltfError unless `part` can be skinned by `skin` (load_gltf calls it for every
        skinned mesh node): JOINTS_0/WEIGHTS_0 present, every vertex's weight sum > 0 and
        every joint index with a non-zero weight < the skin's joint count."""
        _check_skin_part(part, len(self.skins[skin].joints), where or f"skins[{skin}]")


def _check_skin_part(part: GltfPart, n_joints: int, where: str) -> None:
    if part.joints is None or part.weights is None:
        raise GltfError(f"{where}: a skinned primitive needs JOINTS_0 and WEIGHTS_0")
    total = part.weights.sum(axis=1)
    bad = np.nonzero(~(total > 0.0))[0]
    if bad.size:
        raise GltfError(f"{where}: the weights of vertex {int(bad[0])} sum to {float(total[bad[0]])!r}"
                        " (must be > 0)")
    used = part.weights != 0.0
    out = used & ((part.joints >= n_joints) | (part.joints < 0))
    if out.any():
        v = int(np.nonzero(out.any(axis=1))[0][0])
        jj = int(part.joints[v][out[v]][0])
        raise GltfError(f"{where}: vertex {v} uses joint {jj}, but the skin has {n_joints} joints")


# ---------------------------------------------------------------- reading

def _fail(msg: str):
    raise GltfError(msg)


def _read_regular(path: Path, what: str) -> bytes:
    try:
        st = os.stat(path)
    except OSError as e:
        raise GltfError(f"{what}: cannot read {path}: {e.strerror or e}") from None
    if not stat.S_ISREG(st.st_mode):
        raise GltfError(f"{what}: {path} is not a regular file")
    if st.st_size > MAX_ASSET_BYTES:
        raise GltfError(f"{what}: {path} is {st.st_size} bytes, more than the limit of {MAX_ASSET_BYTES}")
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_ASSET_BYTES + 1)
    except OSError as e:
        raise GltfError(f"{what}: cannot read {path}: {e.strerror or e}") from None
    if len(data) > MAX_ASSET_BYTES:
        raise GltfError(f"{what}: {path} is more than the limit of {MAX_ASSET_BYTES} bytes")
    return data


def _parse_glb(data: bytes) -> tuple[dict, bytes | None]:
    if len(data) < 12:
        _fail(f"GLB: truncated header ({len(data)} bytes, expected 12)")
    magic, version, length = struct.unpack_from("<III", data, 0)
    if magic != _GLB_MAGIC:
        _fail("GLB: bad magic (expected 'glTF')")
    if version != 2:
        _fail(f"GLB: header version {version}, expected 2")
    if length > len(data):
        _fail(f"GLB: header length {length} exceeds the file ({len(data)} bytes): truncated")
    if length < 20:
        _fail(f"GLB: header length {length} leaves no room for the JSON chunk")
    pos, js, binary, k = 12, None, None, 0
    while pos < length:
        if pos + 8 > length:
            _fail(f"GLB: chunk {k}: truncated chunk header at byte {pos}")
        clen, ctype = struct.unpack_from("<II", data, pos)
        if pos + 8 + clen > length:
            _fail(f"GLB: chunk {k}: length {clen} at byte {pos} exceeds the file ({length} bytes): truncated")
        body = data[pos + 8: pos + 8 + clen]
        if k == 0:
            if ctype != _CHUNK_JSON:
                _fail("GLB: the first chunk is not JSON")
            js = body
        elif ctype == _CHUNK_JSON:
            _fail(f"GLB: chunk {k}: a second JSON chunk")
        elif ctype == _CHUNK_BIN:
            if binary is not None:
                _fail(f"GLB: chunk {k}: a second BIN chunk")
            if k != 1:
                _fail(f"GLB: chunk {k}: the BIN chunk must come second")
            binary = body
        pos += 8 + clen
        k += 1
    if js is None:
        _fail("GLB: no JSON chunk")
    return _parse_json(js.rstrip(b" \t\r\n\x00"), "GLB JSON chunk"), binary


def _reject_constant(name):
    raise ValueError(f"{name} is not JSON")


def _parse_json(raw: bytes, what: str) -> dict:
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise GltfError(f"{what}: not UTF-8 ({e.reason} at byte {e.start})") from None
    if text.startswith("\ufeff"):
        text = text[1:]
    try:
        doc = json.loads(text, parse_constant=_reject_constant)
    except json.JSONDecodeError as e:
        raise GltfError(f"{what}: JSON syntax error at line {e.lineno} column {e.colno}: {e.msg}") from None
    except (ValueError, RecursionError) as e:
        raise GltfError(f"{what}: bad JSON: {str(e)[:100] or type(e).__name__}") from None
    if not isinstance(doc, dict):
        _fail(f"{what}: the top level is not a JSON object")
    return doc


# ---- typed access to the JSON, every mistake named

_REQ = object()


def _is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_num(v) -> bool:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:                      # an integer beyond float range
        return False


def _obj(v, where: str) -> dict:
    if not isinstance(v, dict):
        _fail(f"{where}: expected a JSON object")
    return v


def _int(o: dict, key: str, where: str, default=_REQ, lo: int = 0, hi: int | None = None):
    v = o.get(key, default)
    if v is _REQ:
        _fail(f"{where}: missing {key}")
    if v is default and default is None:
        return None
    if not _is_int(v) or v < lo or (hi is not None and v > hi):
        rng = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
        _fail(f"{where}.{key}: expected an integer {rng}, got {_show(v)}")
    return v


def _ref(o: dict, key: str, where: str, items: list, name: str, required=False):
    """An index into the top-level array `name` (length len(items))."""
    if key not in o:
        if required:
            _fail(f"{where}: missing {key}")
        return None
    v = o[key]
    if not _is_int(v) or not 0 <= v < len(items):
        _fail(f"{where}.{key}: {_show(v)} is not an index of {name} ({len(items)} entries)")
    return v


def _list(o: dict, key: str, where: str, required=False) -> list:
    if key not in o:
        if required:
            _fail(f"{where}: missing {key}")
        return []
    v = o[key]
    if not isinstance(v, list):
        _fail(f"{where}.{key}: expected an array")
    if len(v) > MAX_ITEMS:
        _fail(f"{where}.{key}: {len(v)} entries, more than the limit of {MAX_ITEMS}")
    return v


def _nums(o: dict, key: str, where: str, n: int, default) -> np.ndarray:
    if key not in o:
        return np.array(default, dtype=np.float64)
    v = o[key]
    if not isinstance(v, list) or len(v) != n or not all(_is_num(x) for x in v):
        _fail(f"{where}.{key}: expected {n} finite numbers")
    return np.array(v, dtype=np.float64)


def _str(o: dict, key: str, where: str, default=None):
    v = o.get(key, default)
    if v is not default and not isinstance(v, str):
        _fail(f"{where}.{key}: expected a string")
    return v


def _show(v) -> str:
    s = json.dumps(v) if not isinstance(v, float) or math.isfinite(v) else repr(v)
    return s if len(s) <= 40 else s[:37] + "..."


# ---- the reader

class _Reader:
    def __init__(self, path: Path):
        self.path = Path(path)
        self.folder = self.path.parent
        self.ignored: list[str] = []
        self.components = 0
        self.image_pixels = 0
        self.part_vertices = 0
        self.part_triangles = 0
        self.file_cache: dict[str, bytes] = {}
        self.buffer_cache: dict[int, bytes] = {}
        self.view_cache: dict[int, tuple[bytes, int, int, int | None]] = {}
        self.accessor_cache: dict[int, np.ndarray] = {}
        self.image_cache: dict[int, np.ndarray] = {}
        self.glb_bin: bytes | None = None

    def ignore(self, what: str) -> None:
        if what not in self.ignored:
            self.ignored.append(what)

    # -- top level

    def load(self) -> GltfAsset:
        data = _read_regular(self.path, "asset")
        if data[:4] == b"glTF" or self.path.suffix.lower() == ".glb":
            doc, self.glb_bin = _parse_glb(data)
        else:
            doc = _parse_json(data, "JSON")
        self.doc = doc
        self._check_depth(doc)
        asset = _obj(doc.get("asset"), "asset") if "asset" in doc else _fail("missing asset")
        version = asset.get("version")
        if version != "2.0":
            _fail(f"asset.version is {_show(version)}, expected exactly \"2.0\"")
        self.extensions()
        for key in ("buffers", "bufferViews", "accessors", "meshes", "materials", "textures",
                    "images", "skins", "animations", "nodes", "scenes", "cameras", "samplers"):
            if key in doc and not isinstance(doc[key], list):
                _fail(f"{key}: expected an array")
            if len(doc.get(key, [])) > MAX_ITEMS:
                _fail(f"{key}: {len(doc[key])} entries, more than the limit of {MAX_ITEMS}")
        self.buffers = [_obj(b, f"buffers[{i}]") for i, b in enumerate(doc.get("buffers", []))]
        self.views = [_obj(b, f"bufferViews[{i}]") for i, b in enumerate(doc.get("bufferViews", []))]
        self.accessors = [_obj(b, f"accessors[{i}]") for i, b in enumerate(doc.get("accessors", []))]
        self.images = [_obj(b, f"images[{i}]") for i, b in enumerate(doc.get("images", []))]
        self.textures = [_obj(b, f"textures[{i}]") for i, b in enumerate(doc.get("textures", []))]
        if doc.get("cameras"):
            self.ignore("cameras")
        nodes = self.nodes()
        roots = self.scene(nodes)
        materials = self.materials()
        meshes = self.meshes(len(materials))
        skins = self.skins(len(nodes))
        for nd in nodes:
            if nd.mesh is not None and nd.mesh >= len(meshes):
                _fail(f"nodes[{nd.index}].mesh: {nd.mesh} is not an index of meshes ({len(meshes)} entries)")
            if nd.skin is not None and nd.skin >= len(skins):
                _fail(f"nodes[{nd.index}].skin: {nd.skin} is not an index of skins ({len(skins)} entries)")
        animations = self.animations(nodes)
        asset_obj = GltfAsset(self.path, nodes, meshes, materials, skins, animations, roots, self.ignored)
        self.check_scene_size(asset_obj)
        return asset_obj

    def _check_depth(self, doc) -> None:
        stack = [(doc, 0)]
        while stack:
            v, d = stack.pop()
            if d > MAX_JSON_DEPTH:
                _fail(f"JSON nested more than {MAX_JSON_DEPTH} levels deep")
            if isinstance(v, dict):
                stack.extend((x, d + 1) for x in v.values())
            elif isinstance(v, list):
                stack.extend((x, d + 1) for x in v)

    def extensions(self) -> None:
        used = self.doc.get("extensionsUsed", [])
        req = self.doc.get("extensionsRequired", [])
        for key, v in (("extensionsUsed", used), ("extensionsRequired", req)):
            if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
                _fail(f"{key}: expected an array of strings")
        for name in req:
            if name in ("KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression"):
                _fail(f"extensionsRequired: {name} (compressed geometry) is not supported")
            if not (name.startswith("KHR_materials_") or name in _TOLERATED_REQUIRED):
                _fail(f"extensionsRequired: {name} is not supported")
        for name in list(used) + list(req):
            if name.startswith("KHR_materials_"):
                self.ignore("KHR_materials_* extensions")
            elif name == "KHR_mesh_quantization":
                pass
            else:
                self.ignore(name)

    # -- buffers, views, accessors

    def external(self, uri: str, where: str) -> bytes:
        if uri.startswith("data:"):
            return self.data_uri(uri, where)
        parsed = urllib.parse.urlsplit(uri)
        if parsed.scheme or parsed.netloc:
            _fail(f"{where}.uri: {_show(uri)}: only relative file paths and data URIs are supported")
        rel = urllib.parse.unquote(parsed.path)
        if not rel or rel.startswith(("/", "\\")) or "\x00" in rel or os.path.isabs(rel):
            _fail(f"{where}.uri: {_show(uri)} is not a relative path")
        base = os.path.realpath(self.folder)
        full = os.path.realpath(os.path.join(base, rel))
        if os.path.commonpath([base, full]) != base:
            _fail(f"{where}.uri: {_show(uri)} leaves the asset's folder")
        if full not in self.file_cache:
            self.file_cache[full] = _read_regular(Path(full), f"{where}.uri")
        return self.file_cache[full]

    def data_uri(self, uri: str, where: str) -> bytes:
        head, sep, payload = uri.partition(",")
        if not sep:
            _fail(f"{where}.uri: bad data URI (no comma)")
        if len(payload) > MAX_ASSET_BYTES * 4 // 3 + 4:
            _fail(f"{where}.uri: data URI of {len(payload)} characters, more than the limit of "
                  f"{MAX_ASSET_BYTES} bytes")
        if head.endswith(";base64"):
            try:
                return base64.b64decode(payload, validate=True)
            except (binascii.Error, ValueError) as e:
                raise GltfError(f"{where}.uri: bad base64 in data URI ({e})") from None
        return urllib.parse.unquote_to_bytes(payload)

    def buffer(self, i: int) -> bytes:
        if i in self.buffer_cache:
            return self.buffer_cache[i]
        b, where = self.buffers[i], f"buffers[{i}]"
        length = _int(b, "byteLength", where, lo=1)
        if "uri" in b:
            uri = _str(b, "uri", where)
            data = self.external(uri, where)
        elif i == 0 and self.glb_bin is not None:
            data = self.glb_bin
        else:
            _fail(f"{where}: no uri (and no GLB BIN chunk)" if i == 0 else f"{where}: no uri")
        if len(data) < length:
            _fail(f"{where}: {len(data)} bytes of data, shorter than its byteLength {length}")
        data = data[:length] if len(data) > length else data
        self.buffer_cache[i] = data
        return data

    def view(self, i: int):
        """(buffer bytes, offset, length, byteStride or None) of bufferViews[i]."""
        if i in self.view_cache:
            return self.view_cache[i]
        v, where = self.views[i], f"bufferViews[{i}]"
        b = _ref(v, "buffer", where, self.buffers, "buffers", required=True)
        offset = _int(v, "byteOffset", where, 0)
        length = _int(v, "byteLength", where, lo=1)
        stride = _int(v, "byteStride", where, None, lo=4, hi=252)
        if stride is not None and stride % 4:
            _fail(f"{where}.byteStride: {stride} is not a multiple of 4")
        data = self.buffer(b)
        if offset + length > len(data):
            _fail(f"{where}: byteOffset + byteLength = {offset + length} exceeds buffers[{b}] ({len(data)} bytes)")
        self.view_cache[i] = (data, offset, length, stride)
        return self.view_cache[i]

    def accessor(self, i: int, where_used: str, types=None, components=None,
                 normalized_ok=True) -> tuple[np.ndarray, dict]:
        """accessors[i] decoded: (count, components) float64 where the accessor is float or
        normalized, else int64; checked to be of one of `types` and `components`."""
        a, where = self.accessors[i], f"accessors[{i}]"
        ctype = a.get("componentType")
        if not _is_int(ctype) or ctype not in _COMPONENT:
            _fail(f"{where}.componentType: {_show(ctype)} is not a glTF component type")
        atype = a.get("type")
        if not isinstance(atype, str) or atype not in _TYPE:
            _fail(f"{where}.type: {_show(atype)} is not a glTF accessor type")
        norm = a.get("normalized", False)
        if not isinstance(norm, bool):
            _fail(f"{where}.normalized: expected true or false")
        if norm and ctype in (G.FLOAT, G.UNSIGNED_INT):
            _fail(f"{where}: normalized is not allowed for componentType {ctype}")
        if types is not None and atype not in types:
            _fail(f"{where_used}: accessors[{i}] is {atype}, expected {' or '.join(types)}")
        if components is not None:
            ok = ctype in components and (ctype == G.FLOAT or normalized_ok is None
                                          or normalized_ok == norm)
            if not ok:
                _fail(f"{where_used}: accessors[{i}] has componentType {ctype}"
                      f"{' (normalized)' if norm else ''}, not allowed here")
        if i in self.accessor_cache:
            return self.accessor_cache[i], a
        count = _int(a, "count", where, lo=1)
        ncomp, rows = _TYPE[atype]
        if count * ncomp > MAX_ACCESSOR_COMPONENTS - self.components:
            _fail(f"{where}: count {count} makes the asset larger than the limit of "
                  f"{MAX_ACCESSOR_COMPONENTS} decoded components")
        dt = _COMPONENT[ctype]
        cs = dt.itemsize
        if rows:
            col = -(-rows * cs // 4) * 4            # matrix columns start on 4-byte boundaries
            offsets = [(c // rows) * col + (c % rows) * cs for c in range(ncomp)]
            esize = rows * col
        else:
            offsets = [c * cs for c in range(ncomp)]
            esize = ncomp * cs
        view_i = _ref(a, "bufferView", where, self.views, "bufferViews")
        byte_offset = _int(a, "byteOffset", where, 0)
        if view_i is None:
            if "byteOffset" in a and byte_offset:
                _fail(f"{where}: byteOffset without bufferView")
            raw = np.zeros((count, ncomp), dtype=dt)
        else:
            data, voff, vlen, vstride = self.view(view_i)
            stride = esize if vstride is None else vstride
            if stride < esize:
                _fail(f"{where}: bufferViews[{view_i}].byteStride {stride} is smaller than the element ({esize} bytes)")
            need = byte_offset + (count - 1) * stride + esize
            if need > vlen:
                _fail(f"{where}: byteOffset + (count - 1) * stride + element size = {need} exceeds "
                      f"bufferViews[{view_i}] ({vlen} bytes)")
            raw = self._gather(data, voff + byte_offset, count, stride, offsets, dt)
        if "sparse" in a:
            self._sparse(a, i, raw, count, ncomp, offsets, esize, dt)
        self.components += count * ncomp
        if ctype == G.FLOAT:
            out = raw.astype(np.float64)
        elif norm:
            out = raw.astype(np.float64)
            if ctype in (G.BYTE, G.SHORT):
                out = np.maximum(out / _NORM_DIVISOR[ctype], -1.0)
            else:
                out /= _NORM_DIVISOR[ctype]
        else:
            out = raw.astype(np.int64)
        out.flags.writeable = False
        self.accessor_cache[i] = out
        return out, a

    @staticmethod
    def _gather(data, start, count, stride, offsets, dt) -> np.ndarray:
        ncomp = len(offsets)
        if offsets == [c * dt.itemsize for c in range(ncomp)]:
            arr = np.ndarray((count, ncomp), dtype=dt, buffer=data, offset=start,
                             strides=(stride, dt.itemsize))
            return arr.copy()
        out = np.empty((count, ncomp), dtype=dt)
        for c, o in enumerate(offsets):
            out[:, c] = np.ndarray((count,), dtype=dt, buffer=data, offset=start + o, strides=(stride,))
        return out

    def _sparse(self, a, i, raw, count, ncomp, offsets, esize, dt) -> None:
        where = f"accessors[{i}].sparse"
        sp = _obj(a["sparse"], where)
        n = _int(sp, "count", where, lo=1, hi=count)
        ind = _obj(sp.get("indices"), f"{where}.indices") if "indices" in sp else _fail(f"{where}: missing indices")
        val = _obj(sp.get("values"), f"{where}.values") if "values" in sp else _fail(f"{where}: missing values")
        ict = ind.get("componentType")
        if ict not in (G.UNSIGNED_BYTE, G.UNSIGNED_SHORT, G.UNSIGNED_INT) or not _is_int(ict):
            _fail(f"{where}.indices.componentType: {_show(ict)} is not UNSIGNED_BYTE, _SHORT or _INT")
        idt = _COMPONENT[ict]
        parts = []
        for sub, d, off_list, size in (("indices", ind, [0], idt.itemsize), ("values", val, offsets, esize)):
            w = f"{where}.{sub}"
            vi = _ref(d, "bufferView", w, self.views, "bufferViews", required=True)
            bo = _int(d, "byteOffset", w, 0)
            data, voff, vlen, _ = self.view(vi)
            need = bo + n * size
            if need > vlen:
                _fail(f"{w}: byteOffset + count * element size = {need} exceeds bufferViews[{vi}] ({vlen} bytes)")
            parts.append(self._gather(data, voff + bo, n, size, off_list, idt if sub == "indices" else dt))
        idx = parts[0][:, 0].astype(np.int64)
        if idx.size > 1 and not (np.diff(idx) > 0).all():
            _fail(f"{where}.indices: not strictly increasing")
        if idx.size and idx[-1] >= count:
            _fail(f"{where}.indices: index {int(idx[-1])} out of range of the accessor's count {count}")
        raw[idx] = parts[1]

    # -- nodes and the scene

    def nodes(self) -> list[GltfNode]:
        raw = self.doc.get("nodes", [])
        if len(raw) > MAX_NODES:
            _fail(f"nodes: {len(raw)} nodes, more than the limit of {MAX_NODES}")
        n = len(raw)
        out: list[GltfNode] = []
        parent: list[int | None] = [None] * n
        for i, nd in enumerate(raw):
            where = f"nodes[{i}]"
            _obj(nd, where)
            name = nd.get("name")
            name = name if isinstance(name, str) and name else f"node{i}"
            children = _list(nd, "children", where)
            for c in children:
                if not _is_int(c) or not 0 <= c < n:
                    _fail(f"{where}.children: {_show(c)} is not an index of nodes ({n} entries)")
                if c == i:
                    _fail(f"{where}.children: the node is its own child")
                if parent[c] is not None:
                    _fail(f"nodes[{c}] has two parents (nodes[{parent[c]}] and nodes[{i}])")
                parent[c] = i
            matrix = None
            if "matrix" in nd:
                m = _nums(nd, "matrix", where, 16, None)
                matrix = m.reshape(4, 4).T.copy()          # column-major in the file
            t = _nums(nd, "translation", where, 3, [0.0, 0.0, 0.0])
            r = _nums(nd, "rotation", where, 4, [0.0, 0.0, 0.0, 1.0])
            nr = float(np.sqrt(r @ r))
            if nr == 0.0:
                _fail(f"{where}.rotation: a zero quaternion")
            r = r / nr
            s = _nums(nd, "scale", where, 3, [1.0, 1.0, 1.0])
            mesh = _int(nd, "mesh", where, None)
            skin = _int(nd, "skin", where, None)
            if "camera" in nd:
                self.ignore("cameras")
            if "weights" in nd:
                self.ignore("morph target weights")
            out.append(GltfNode(i, name, None, [int(c) for c in children], matrix, t, r, s, mesh, skin))
        for i, p in enumerate(parent):
            out[i].parent = p
        # cycles: with one parent each, the nodes on (or below) a cycle are exactly those
        # that a walk down from the parentless nodes never reaches
        reached = [False] * n
        stack = [i for i in range(n) if parent[i] is None]
        while stack:
            i = stack.pop()
            reached[i] = True
            stack.extend(out[i].children)
        if not all(reached):
            _fail(f"nodes[{reached.index(False)}]: the node graph has a cycle")
        return out

    def scene(self, nodes: list[GltfNode]) -> list[int]:
        scenes = self.doc.get("scenes", [])
        if "scene" in self.doc:
            s = _ref(self.doc, "scene", "scene", scenes, "scenes")
            where = f"scenes[{s}]"
        elif scenes:
            s, where = 0, "scenes[0]"
        else:
            return [nd.index for nd in nodes if nd.parent is None]
        sc = _obj(scenes[s], where)
        roots = []
        for r in _list(sc, "nodes", where):
            if not _is_int(r) or not 0 <= r < len(nodes):
                _fail(f"{where}.nodes: {_show(r)} is not an index of nodes ({len(nodes)} entries)")
            if nodes[r].parent is not None:
                _fail(f"{where}.nodes: nodes[{r}] is not a root (its parent is nodes[{nodes[r].parent}])")
            if r in roots:
                _fail(f"{where}.nodes: nodes[{r}] listed twice")
            roots.append(int(r))
        return roots

    # -- materials and images

    def materials(self) -> list[GltfMaterial]:
        out = []
        for i, m in enumerate(self.doc.get("materials", [])):
            where = f"materials[{i}]"
            _obj(m, where)
            name = m.get("name")
            name = name if isinstance(name, str) and name else f"material{i}"
            pbr = _obj(m.get("pbrMetallicRoughness", {}), f"{where}.pbrMetallicRoughness")
            color = _nums(pbr, "baseColorFactor", f"{where}.pbrMetallicRoughness", 4, [1.0, 1.0, 1.0, 1.0])
            image = None
            if "baseColorTexture" in pbr:
                ti = _obj(pbr["baseColorTexture"], f"{where}.pbrMetallicRoughness.baseColorTexture")
                t = _ref(ti, "index", f"{where}.pbrMetallicRoughness.baseColorTexture",
                         self.textures, "textures", required=True)
                tex = self.textures[t]
                src = _ref(tex, "source", f"textures[{t}]", self.images, "images")
                if src is None:
                    self.ignore("textures without a core image source")
                else:
                    image = self.image(src)
            for key, what in (("normalTexture", "normal textures"), ("emissiveTexture", "emissive"),
                              ("occlusionTexture", "occlusion textures")):
                if key in m:
                    self.ignore(what)
            if "metallicRoughnessTexture" in pbr:
                self.ignore("metallic-roughness textures")
            if m.get("alphaMode", "OPAQUE") != "OPAQUE" or (color[3] != 1.0):
                self.ignore("alpha")
            if isinstance(m.get("extensions"), dict) and m["extensions"]:
                self.ignore("KHR_materials_* extensions")
            out.append(GltfMaterial(color, image, name))
        return out

    def image(self, i: int) -> np.ndarray:
        if i in self.image_cache:
            return self.image_cache[i]
        im, where = self.images[i], f"images[{i}]"
        if "uri" in im:
            data = self.external(_str(im, "uri", where), where)
        elif "bufferView" in im:
            vi = _ref(im, "bufferView", where, self.views, "bufferViews", required=True)
            buf, off, length, _ = self.view(vi)
            data = buf[off: off + length]
        else:
            _fail(f"{where}: neither uri nor bufferView")
        self.image_cache[i] = _decode_image(data, where, self)
        return self.image_cache[i]

    # -- meshes

    def meshes(self, n_materials: int) -> list[list[GltfPart]]:
        out = []
        for mi, m in enumerate(self.doc.get("meshes", [])):
            where = f"meshes[{mi}]"
            _obj(m, where)
            prims = _list(m, "primitives", where, required=True)
            if not prims:
                _fail(f"{where}.primitives: empty")
            if "weights" in m:
                self.ignore(f"morph targets ({where})")
            parts = [self.primitive(_obj(p, f"{where}.primitives[{k}]"), f"{where}.primitives[{k}]",
                                    n_materials, mi) for k, p in enumerate(prims)]
            out.append(parts)
        return out

    def primitive(self, p: dict, where: str, n_materials: int, mi: int) -> GltfPart:
        mode = p.get("mode", G.TRIANGLES)
        if mode != G.TRIANGLES or not _is_int(mode):
            _fail(f"{where}: primitives must be triangles (mode 4), this one has mode {_show(mode)}")
        attrs = _obj(p.get("attributes"), f"{where}.attributes") if "attributes" in p else _fail(f"{where}: missing attributes")
        if "targets" in p:
            self.ignore(f"morph targets (meshes[{mi}])")
        for k in attrs:
            if k.startswith("COLOR_"):
                self.ignore("vertex colours")

        def acc(name, types, comps, norm_ok=None):
            if name not in attrs:
                return None
            i = _ref(attrs, name, f"{where}.attributes", self.accessors, "accessors")
            return self.accessor(i, f"{where}.attributes.{name}", types, comps, norm_ok)[0]

        pos = acc("POSITION", ("VEC3",), None)
        if pos is None:
            _fail(f"{where}.attributes: no POSITION")
        n = pos.shape[0]
        if pos.dtype != np.float64:
            pos = pos.astype(np.float64)           # KHR_mesh_quantization: non-normalized ints
        if not np.isfinite(pos).all():
            _fail(f"{where}.attributes.POSITION: non-finite values")

        def same_count(arr, name):
            if arr is not None and arr.shape[0] != n:
                _fail(f"{where}.attributes.{name}: {arr.shape[0]} elements, POSITION has {n}")
            if arr is not None and arr.dtype == np.float64 and not np.isfinite(arr).all():
                _fail(f"{where}.attributes.{name}: non-finite values")
            return arr

        nrm = same_count(acc("NORMAL", ("VEC3",), (G.FLOAT, G.BYTE, G.SHORT), True), "NORMAL")
        uv = same_count(acc("TEXCOORD_0", ("VEC2",), _FLOATISH, None), "TEXCOORD_0")
        if uv is not None and uv.dtype != np.float64:
            uv = uv.astype(np.float64)             # KHR_mesh_quantization: non-normalized ints
        joints = weights = None
        for s in ("0", "1"):
            j = same_count(acc(f"JOINTS_{s}", ("VEC4",), (G.UNSIGNED_BYTE, G.UNSIGNED_SHORT), False),
                           f"JOINTS_{s}")
            w = same_count(acc(f"WEIGHTS_{s}", ("VEC4",), (G.FLOAT, G.UNSIGNED_BYTE, G.UNSIGNED_SHORT), True),
                           f"WEIGHTS_{s}")
            if (j is None) != (w is None):
                _fail(f"{where}.attributes: JOINTS_{s} and WEIGHTS_{s} must come together")
            if j is None:
                break
            joints = j if joints is None else np.concatenate([joints, j], axis=1)
            weights = w if weights is None else np.concatenate([weights, w], axis=1)
        if "indices" in p:
            ii = _ref(p, "indices", where, self.accessors, "accessors")
            idx, _ = self.accessor(ii, f"{where}.indices", ("SCALAR",),
                                   (G.UNSIGNED_BYTE, G.UNSIGNED_SHORT, G.UNSIGNED_INT), False)
            idx = idx[:, 0]
            if idx.size % 3:
                _fail(f"{where}.indices: {idx.size} indices, not a multiple of 3")
            if idx.size and int(idx.max()) >= n:
                _fail(f"{where}.indices: index {int(idx.max())} out of range of the {n} vertices")
            faces = idx.reshape(-1, 3)
        else:
            if n % 3:
                _fail(f"{where}: {n} vertices without indices, not a multiple of 3")
            if self.part_vertices + n > MAX_VERTICES:
                _fail(f"{where}: the asset's primitives have more than {MAX_VERTICES} vertices together")
            faces = np.arange(n, dtype=np.int64).reshape(-1, 3)
        self.part_vertices += n
        self.part_triangles += faces.shape[0]
        if self.part_vertices > MAX_VERTICES or self.part_triangles > MAX_TRIANGLES:
            _fail(f"{where}: the asset's primitives have more than {MAX_VERTICES} vertices or "
                  f"{MAX_TRIANGLES} triangles together")
        mat = _ref(p, "material", where, range(n_materials), "materials")
        part = GltfPart(pos, nrm, uv, faces, joints, weights, mat)
        for arr in (pos, nrm, uv, faces, joints, weights):
            if arr is not None:
                arr.flags.writeable = False
        return part

    # -- skins

    def skins(self, n_nodes: int) -> list[GltfSkin]:
        out = []
        for si, s in enumerate(self.doc.get("skins", [])):
            where = f"skins[{si}]"
            _obj(s, where)
            joints = _list(s, "joints", where, required=True)
            if not joints:
                _fail(f"{where}.joints: a skin with no joints")
            if len(joints) > MAX_JOINTS:
                _fail(f"{where}.joints: {len(joints)} joints, more than the limit of {MAX_JOINTS}")
            for j in joints:
                if not _is_int(j) or not 0 <= j < n_nodes:
                    _fail(f"{where}.joints: {_show(j)} is not an index of nodes ({n_nodes} entries)")
            if len(set(joints)) != len(joints):
                _fail(f"{where}.joints: a node listed twice")
            J = len(joints)
            if "inverseBindMatrices" in s:
                ai = _ref(s, "inverseBindMatrices", where, self.accessors, "accessors")
                m, _ = self.accessor(ai, f"{where}.inverseBindMatrices", ("MAT4",), (G.FLOAT,))
                if m.shape[0] < J:
                    _fail(f"{where}.inverseBindMatrices: {m.shape[0]} matrices for {J} joints")
                if not np.isfinite(m).all():
                    _fail(f"{where}.inverseBindMatrices: non-finite values")
                ibm = m[:J].reshape(J, 4, 4).transpose(0, 2, 1).copy()
            else:
                ibm = np.tile(np.eye(4), (J, 1, 1))
            if "skeleton" in s:
                _ref(s, "skeleton", where, range(n_nodes), "nodes")
            out.append(GltfSkin([int(j) for j in joints], ibm))
        return out

    # -- animations

    def animations(self, nodes: list[GltfNode]) -> list[GltfAnimation]:
        out = []
        for ai, an in enumerate(self.doc.get("animations", [])):
            where = f"animations[{ai}]"
            _obj(an, where)
            name = an.get("name")
            name = name if isinstance(name, str) and name else f"animation{ai}"
            samplers = [_obj(s, f"{where}.samplers[{k}]") for k, s in enumerate(_list(an, "samplers", where))]
            times: dict[int, np.ndarray] = {}
            for k, s in enumerate(samplers):
                times[k] = self.key_times(s, f"{where}.samplers[{k}]")
            span = None
            if times:
                span = (min(float(t[0]) for t in times.values()), max(float(t[-1]) for t in times.values()))
            built: dict[tuple[int, str], GltfSampler] = {}
            channels = []
            for c, ch in enumerate(_list(an, "channels", where)):
                cw = f"{where}.channels[{c}]"
                _obj(ch, cw)
                k = _ref(ch, "sampler", cw, samplers, f"{where}.samplers", required=True)
                tgt = _obj(ch.get("target"), f"{cw}.target") if "target" in ch else _fail(f"{cw}: missing target")
                path = tgt.get("path")
                if path not in TRS_PATHS + ("weights",):
                    if isinstance(path, str) and path:
                        self.ignore(f"{path} channels")
                        continue
                    _fail(f"{cw}.target.path: {_show(path)} is not translation, rotation, scale or weights")
                node = _ref(tgt, "node", f"{cw}.target", nodes, "nodes")
                if path == "weights":
                    self.ignore("weights channels")
                    continue
                if node is None:                    # targeted through an extension: ignored
                    continue
                if (k, path) not in built:
                    built[(k, path)] = self.sampler(samplers[k], times[k], path, f"{where}.samplers[{k}]")
                channels.append(GltfChannel(node, path, built[(k, path)]))
            out.append(GltfAnimation(name, channels, span))
        return out

    def key_times(self, s: dict, where: str) -> np.ndarray:
        i = _ref(s, "input", where, self.accessors, "accessors", required=True)
        t, _ = self.accessor(i, f"{where}.input", ("SCALAR",), (G.FLOAT,))
        t = t[:, 0]
        if not np.isfinite(t).all():
            _fail(f"{where}.input: non-finite key times")
        if t.size > 1 and not (np.diff(t) > 0).all():
            k = int(np.nonzero(~(np.diff(t) > 0))[0][0])
            _fail(f"{where}.input: key times not strictly increasing (key {k + 1}: {float(t[k + 1])!r} after {float(t[k])!r})")
        return t

    def sampler(self, s: dict, times: np.ndarray, path: str, where: str) -> GltfSampler:
        interp = s.get("interpolation", "LINEAR")
        if interp not in INTERPOLATIONS:
            _fail(f"{where}.interpolation: {_show(interp)} is not STEP, LINEAR or CUBICSPLINE")
        o = _ref(s, "output", where, self.accessors, "accessors", required=True)
        c = 4 if path == "rotation" else 3
        comps = (G.FLOAT, G.BYTE, G.UNSIGNED_BYTE, G.SHORT, G.UNSIGNED_SHORT) if path == "rotation" else (G.FLOAT,)
        v, _ = self.accessor(o, f"{where}.output", (f"VEC{c}",), comps, True)
        n = times.shape[0]
        per = 3 if interp == "CUBICSPLINE" else 1
        if v.shape[0] != per * n:
            _fail(f"{where}: {n} key times but {v.shape[0]} output values "
                  f"(expected {per * n} for {interp})")
        if not np.isfinite(v).all():
            _fail(f"{where}.output: non-finite key values")
        if interp == "CUBICSPLINE":
            v = v.reshape(n, 3, c)
            if path == "rotation" and not (np.einsum("ij,ij->i", v[:, 1], v[:, 1]) > 0).all():
                _fail(f"{where}.output: a zero rotation quaternion")
        elif path == "rotation" and not (np.einsum("ij,ij->i", v, v) > 0).all():
            _fail(f"{where}.output: a zero rotation quaternion")
        return GltfSampler(times, v, interp)

    # -- totals

    def check_scene_size(self, asset: GltfAsset) -> None:
        nv = nt = 0
        for i in asset.mesh_nodes():
            nd = asset.nodes[i]
            for part in asset.meshes[nd.mesh]:
                nv += part.positions.shape[0]
                nt += part.faces.shape[0]
            if nv > MAX_VERTICES or nt > MAX_TRIANGLES:
                _fail(f"the scene's mesh nodes have more than {MAX_VERTICES} vertices or "
                      f"{MAX_TRIANGLES} triangles")
            if nd.skin is not None:
                for k, part in enumerate(asset.meshes[nd.mesh]):
                    _check_skin_part(part, len(asset.skins[nd.skin].joints),
                                     f"nodes[{i}] (skins[{nd.skin}], meshes[{nd.mesh}].primitives[{k}])")


_SRGB_LUT8 = None


def _srgb_lut(levels: int) -> np.ndarray:
    c = np.arange(levels, dtype=np.float64) / (levels - 1)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def _decode_image(data: bytes, where: str, reader: _Reader) -> np.ndarray:
    """An embedded or referenced PNG/JPEG -> (H, W, 3) float32 linear RGB (sRGB decoded
    through a lookup table), top row first. Pixel counts checked from the header first."""
    global _SRGB_LUT8
    from PIL import Image
    try:
        with Image.open(io.BytesIO(data), formats=("PNG", "JPEG")) as im:
            w, h = im.size
            if w <= 0 or h <= 0:
                _fail(f"{where}: an image with no pixels")
            if w * h > MAX_IMAGE_PIXELS:
                _fail(f"{where}: {w}x{h} pixels, more than the limit of {MAX_IMAGE_PIXELS}")
            if reader.image_pixels + w * h > MAX_TOTAL_IMAGE_PIXELS:
                _fail(f"{where}: the asset's images exceed {MAX_TOTAL_IMAGE_PIXELS} pixels together")
            reader.image_pixels += w * h
            if im.mode in ("I;16", "I;16L", "I;16B", "I;16N", "I"):
                grey = np.clip(np.asarray(im, dtype=np.int64), 0, 65535)
                lin = _srgb_lut(65536)[grey]
                return np.repeat(lin[..., None], 3, axis=2)
            rgb = np.asarray(im.convert("RGB"), dtype=np.uint8)
    except GltfError:
        raise
    except Exception as e:                       # Pillow raises many types for bad data
        raise GltfError(f"{where}: cannot decode the image ({type(e).__name__}: {str(e)[:80]})") from None
    if _SRGB_LUT8 is None:
        _SRGB_LUT8 = _srgb_lut(256)
    return _SRGB_LUT8[rgb]


def load_gltf(path) -> GltfAsset:
    """Read and check a .gltf or .glb; GltfError (one line) for anything malformed."""
    try:
        return _Reader(Path(path)).load()
    except GltfError:
        raise
    except MemoryError:
        raise GltfError("out of memory while reading the asset") from None
    except RecursionError:
        raise GltfError("the asset is nested too deeply") from None
    except Exception as e:                       # a safety net: never anything but GltfError
        raise GltfError(f"malformed asset ({type(e).__name__}: {str(e)[:100]})") from None


__all__ = ["GltfError", "GltfAsset", "GltfMaterial", "GltfPart", "GltfNode", "GltfSkin",
           "GltfSampler", "GltfChannel", "GltfAnimation", "MAX_ASSET_BYTES", "load_gltf",
           "sample", "skin_vertices", "slerp_xyzw", "quat_matrices", "trs_matrices"]
