"""Regenerates scenes/assets/rover.glb: a toy rover (glTF 2.0, binary) for scenes/rover.toml.
Run `python -m scenes.make_gltf_assets` (or `--out DIR`); the output is committed, and
tests/test_gltf_assets.py checks that this script rebuilds it byte for byte.

The asset (metres, Y-up, the rover's front faces +Z as glTF's assets do, its right -X).
The geometry below is designed in a frame whose front is +X and right +Z (the design
frame), and turned into the asset's by TO_ASSET (90 degrees about Y) as it is written:

    vehicle                   root; animation "drive": translation + rotation keys (the
                              first key turns the rover to face +X, along its path)
      body                    chassis + cabin (two materials) + side decals (PNG texture)
      steer_fl -> wheel_fl    front wheels: "drive" steers the knuckle about Y (Ackermann)
      steer_fr -> wheel_fr      and spins the wheel about its axle, local X
      wheel_rl, wheel_rr      rear wheels: spin only
      arm_j0 -> arm_j1 -> arm_j2 -> arm_tip
                              the crane's joints; animation "swing" turns them; arm_tip is
                              a rigid lamp on the last joint
    arm                       a banded tube skinned to arm_j0..arm_j2 (JOINTS_0/WEIGHTS_0,
                              inverseBindMatrices); a root node, as glTF skins usually are

"drive" (0..5 s): the rover speeds up to 3 m/s along +X, then turns 90 degrees left (to
-Z) on a curve whose curvature rises and falls smoothly, its rear axle on the path; each
wheel turns by the distance its own centre travels over its radius (the inner wheels
slower). "swing" (0..5 s, two periods of 2.5 s): the crane yaws +-50 degrees and bends.
Keys at 30 per second, LINEAR: a wheel turns at most 24 degrees between keys (slerp must
never see 180). Within a 0.04 s shutter a wheel at 10 rad/s turns 23 degrees, over half of
one of its hub's 36-degree sectors, and the arm's tip moves a few centimetres.

Deterministic: fixed sizes and formulas, float32 data, the JSON written in one fixed
order, and the PNG written here with stored (uncompressed) deflate blocks, so no zlib
version can change a byte.
"""
from __future__ import annotations

import argparse
import json
import math
import struct
import zlib
from pathlib import Path

import numpy as np

ASSETS = Path(__file__).resolve().parent / "assets"
GENERATOR = "hybrid-mblur scenes/make_gltf_assets.py"

KEY_RATE = 30                   # keys per second
DURATION = 5.0                  # both animations: [0, DURATION] s
FINE = 3000                     # integration steps per second for the path

# The rover in the design frame (front +X, right +Z; origin on the ground under the rear
# axle). TO_ASSET turns design vectors into the asset's frame (front +Z, right -X).
TO_ASSET = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
WHEEL_R = 0.3                   # wheel radius
WHEEL_W = 0.18                  # wheel width (along its axle)
WHEELBASE = 1.3                 # rear axle x = 0, front axle x = WHEELBASE
HALF_TRACK = 0.55               # wheel centres at z = +-HALF_TRACK
BODY_AT = (0.65, 0.55, 0.0)     # the body node's translation
CHASSIS = ((-1.0, 1.0), (-0.2, 0.2), (-0.42, 0.42))   # x, y, z ranges about BODY_AT
CABIN = ((0.05, 0.75), (0.15, 0.52), (-0.36, 0.36))
ARM_BASE = (0.15, 0.75, 0.0)    # arm_j0: on the chassis top, behind the cabin
ARM_LENGTH = 1.0
ARM_JOINTS = 3                  # joints every ARM_LENGTH / 3 up the tube

# The drive: speed ramps to V_MAX; the turn's curvature is a smooth bump over
# [TURN_FROM, TURN_TO] metres of the rear axle's path, scaled so the heading turns 90 deg.
V_MAX = 3.0
RAMP = 0.8                      # s to reach V_MAX
START = (-6.0, 0.0, 3.5)
TURN_FROM, TURN_TO, TURN_EASE = 4.0, 11.0, 2.0

# glTF enums
FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
LINEAR_FILTER, LINEAR_MIPMAP_LINEAR, REPEAT = 9729, 9987, 10497


# ---------------------------------------------------------------- small maths

def smoothstep(a: float, b: float, x):
    u = np.clip((np.asarray(x, np.float64) - a) / (b - a), 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def to_asset(v) -> np.ndarray:
    """Design-frame vectors (..., 3) in the asset's frame (-0.0 written as 0.0)."""
    return np.asarray(v, np.float64) @ TO_ASSET.T + 0.0


AXLE = to_asset([0.0, 0.0, 1.0])      # the wheels' axle and the arm's bending axis: -X


def quat_axis(axis, angle) -> np.ndarray:
    """(..., 4) x y z w quaternions of rotations by `angle` (radians, array) about `axis`."""
    angle = np.asarray(angle, np.float64)
    axis = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    s, c = np.sin(angle / 2.0), np.cos(angle / 2.0)
    return np.concatenate([s[..., None] * axis, c[..., None]], axis=-1)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b (x y z w), the rotation b first."""
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz], axis=-1)


def continuous(q: np.ndarray) -> np.ndarray:
    """Keys with each quaternion on the same side as the one before (q and -q are the same
    rotation; slerp takes the short way either way, this only keeps the file tidy)."""
    q = q.copy()
    for i in range(1, len(q)):
        if np.dot(q[i - 1], q[i]) < 0:
            q[i] = -q[i]
    return q


def translate(v) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = v
    return m


def quat_matrix(q) -> np.ndarray:
    x, y, z, w = q
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    return m


# ---------------------------------------------------------------- the motion

def key_times() -> np.ndarray:
    return np.arange(int(round(DURATION * KEY_RATE)) + 1, dtype=np.float64) / KEY_RATE


def drive() -> dict:
    """The rover's motion sampled at the key times: vehicle position and yaw, the front
    knuckles' steering angles, each wheel's spin angle (radians, about its axle)."""
    n = int(round(DURATION * FINE))
    t = np.arange(n + 1, dtype=np.float64) / FINE
    dt = 1.0 / FINE
    v = V_MAX * smoothstep(0.0, RAMP, t)
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])   # trapezoids
    bump = smoothstep(TURN_FROM, TURN_FROM + TURN_EASE, s) \
        * (1.0 - smoothstep(TURN_TO - TURN_EASE, TURN_TO, s))
    # curvature k(s) = K bump(s), K such that the heading's integral over the turn is 90
    # degrees (measured on a fine uniform grid in s, independent of the speed profile)
    grid = np.linspace(0.0, TURN_TO + 1.0, 20001)
    gb = smoothstep(TURN_FROM, TURN_FROM + TURN_EASE, grid) \
        * (1.0 - smoothstep(TURN_TO - TURN_EASE, TURN_TO, grid))
    K = (math.pi / 2.0) / float(np.sum(0.5 * (gb[1:] + gb[:-1]) * np.diff(grid)))
    kappa = K * bump
    ds = np.diff(s)
    yaw = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * ds)])
    # forward = Ry(yaw) (1, 0, 0) = (cos yaw, 0, -sin yaw): a left turn (towards -Z) is +yaw
    fx, fz = np.cos(yaw), -np.sin(yaw)
    x = START[0] + np.concatenate([[0.0], np.cumsum(0.5 * (fx[1:] + fx[:-1]) * ds)])
    z = START[2] + np.concatenate([[0.0], np.cumsum(0.5 * (fz[1:] + fz[:-1]) * ds)])
    # Ackermann: the turn's centre is on the left (-Z) at 1/k from the rear axle
    steer_l = np.arctan(WHEELBASE * kappa / (1.0 - HALF_TRACK * kappa))
    steer_r = np.arctan(WHEELBASE * kappa / (1.0 + HALF_TRACK * kappa))
    spins = {}
    for name, (wx, wz) in wheel_offsets().items():
        # the wheel centre's path on the ground plane: vehicle + Ry(yaw) (wx, 0, wz)
        px = x + np.cos(yaw) * wx + np.sin(yaw) * wz
        pz = z - np.sin(yaw) * wx + np.cos(yaw) * wz
        d = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(px), np.diff(pz)))])
        spins[name] = -d / WHEEL_R        # design frame: rolling to +X turns about -Z
    at = np.arange(0, n + 1, FINE // KEY_RATE)
    return {"position": np.stack([x[at], np.full(len(at), START[1]), z[at]], axis=1),
            "yaw": yaw[at], "steer_fl": steer_l[at], "steer_fr": steer_r[at],
            "spin": {k: a[at] for k, a in spins.items()}}


def wheel_offsets() -> dict:
    """Each wheel's centre (x, z) in the vehicle's frame (left is -Z)."""
    return {"wheel_fl": (WHEELBASE, -HALF_TRACK), "wheel_fr": (WHEELBASE, HALF_TRACK),
            "wheel_rl": (0.0, -HALF_TRACK), "wheel_rr": (0.0, HALF_TRACK)}


def swing() -> dict:
    """The crane's joint rotations at the key times (x y z w): arm_j0 yaws about Y and
    pitches about the axle's direction, arm_j1 and arm_j2 bend about it a little later each
    (a travelling wave up the arm)."""
    t = key_times()
    w = 2.0 * math.pi / 2.5                                   # a 2.5 s period
    yaw = math.radians(50.0) * np.sin(w * t)
    pitch = math.radians(-20.0) + math.radians(12.0) * np.sin(2.0 * w * t + 0.5)
    j0 = quat_mul(quat_axis([0, 1, 0], yaw), quat_axis(AXLE, pitch))
    j1 = quat_axis(AXLE, math.radians(30.0) * np.sin(w * t - 0.9))
    j2 = quat_axis(AXLE, math.radians(35.0) * np.sin(w * t - 1.8))
    return {"arm_j0": continuous(j0), "arm_j1": continuous(j1), "arm_j2": continuous(j2)}


# ---------------------------------------------------------------- meshes

def box_faces(ranges, uv_sides: bool = False):
    """A box's six faces as separate quads (flat normals). Returns {"sides": (pos, nrm, uv,
    idx), "rest": (pos, nrm, idx)} where "sides" are the +-Z faces with UVs (u along the
    length, read left to right from either side; v = 0 at the top) when uv_sides, else
    every face is in "rest"."""
    (x0, x1), (y0, y1), (z0, z1) = ranges
    quads = [  # (corners counter-clockwise seen from outside, normal)
        ([(x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)], (1, 0, 0)),
        ([(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], (-1, 0, 0)),
        ([(x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (x0, y1, z0)], (0, 1, 0)),
        ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, -1, 0)),
        ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, 1)),
        ([(x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)], (0, 0, -1)),
    ]
    out = {"sides": ([], [], [], []), "rest": ([], [], [])}
    for corners, normal in quads:
        side = uv_sides and normal[2] != 0
        pos, nrm, *rest = out["sides" if side else "rest"]
        base = len(pos)
        pos.extend(corners)
        nrm.extend([normal] * 4)
        if side:
            # seen from outside, corners run bottom-left, bottom-right, top-right, top-left
            rest[0].extend([(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)])
        rest[-1].extend([base, base + 1, base + 2, base, base + 2, base + 3])
    return out


def wheel_parts(sections: int = 40, spokes: int = 5):
    """The wheel about the design frame's Z (its axle): a tread and tyre walls (dark, the tread with
    light grooves), and on both faces a hub disc in two colours, `spokes` light sectors on
    dark, so its turn shows. Returns {material: (positions, normals, indices)}."""
    r_out, r_hub, h = WHEEL_R, 0.2, WHEEL_W / 2.0
    a = 2.0 * math.pi * np.arange(sections + 1) / sections
    c, s = np.cos(a), np.sin(a)
    parts = {m: ([], [], []) for m in ("tyre", "groove", "hub_light", "hub_dark")}

    def tri(material, p, n):
        pos, nrm, idx = parts[material]
        idx.extend(range(len(pos), len(pos) + 3))
        pos.extend(p)
        nrm.extend(n)

    for i in range(sections):
        j = i + 1
        # tread: a groove every 4th section
        material = "groove" if i % 4 == 0 else "tyre"
        p = [(r_out * c[i], r_out * s[i], -h), (r_out * c[j], r_out * s[j], -h),
             (r_out * c[j], r_out * s[j], h), (r_out * c[i], r_out * s[i], h)]
        n = [(c[i], s[i], 0.0), (c[j], s[j], 0.0), (c[j], s[j], 0.0), (c[i], s[i], 0.0)]
        tri(material, [p[0], p[1], p[2]], [n[0], n[1], n[2]])
        tri(material, [p[0], p[2], p[3]], [n[0], n[2], n[3]])
        hub = "hub_light" if (i * 2 * spokes // sections) % 2 == 0 else "hub_dark"
        for zf, sign in ((h, 1.0), (-h, -1.0)):
            nz = (0.0, 0.0, sign)
            # tyre wall: the ring from r_hub to r_out
            q = [(r_hub * c[i], r_hub * s[i], zf), (r_out * c[i], r_out * s[i], zf),
                 (r_out * c[j], r_out * s[j], zf), (r_hub * c[j], r_hub * s[j], zf)]
            if sign < 0:
                q = q[::-1]
            tri("tyre", [q[0], q[1], q[2]], [nz] * 3)
            tri("tyre", [q[0], q[2], q[3]], [nz] * 3)
            # hub: a fan from the centre
            f = [(0.0, 0.0, zf), (r_hub * c[i], r_hub * s[i], zf), (r_hub * c[j], r_hub * s[j], zf)]
            if sign < 0:
                f = [f[0], f[2], f[1]]
            tri(hub, f, [nz] * 3)
    return parts


def tube(rings: int = 11, sides: int = 12):
    """The crane arm in its bind pose (design frame): a tube up Y from 0 to ARM_LENGTH (radius
    0.055 tapering to 0.035), capped, in bands of two materials; vertex weights to the
    three joints (blended over 0.08 m about each inner joint). Returns {material:
    (positions, normals, joints, weights, indices)} with positions about the joint base."""
    seg = ARM_LENGTH / (rings - 1)
    ys = np.arange(rings) * seg
    radius = 0.055 - 0.02 * ys / ARM_LENGTH
    a = 2.0 * math.pi * np.arange(sides + 1) / sides
    bands = {m: ([], [], [], []) for m in ("arm_red", "arm_white")}

    def weights(y: float):
        step = ARM_LENGTH / ARM_JOINTS
        s1 = float(smoothstep(step - 0.08, step + 0.08, y))
        s2 = float(smoothstep(2 * step - 0.08, 2 * step + 0.08, y))
        return (1.0 - s1, s1 - s2, s2, 0.0)

    def quad(material, p, n, y):
        pos, nrm, wts, idx = bands[material]
        b = len(pos)
        pos.extend(p)
        nrm.extend(n)
        wts.extend(weights(yy) for yy in y)
        idx.extend([b, b + 1, b + 2, b, b + 2, b + 3])

    dr = 0.02 / ARM_LENGTH                       # the taper's slope tilts the normals
    for r in range(rings - 1):
        material = "arm_red" if r % 2 == 0 else "arm_white"
        y0, y1, r0, r1 = ys[r], ys[r + 1], radius[r], radius[r + 1]
        for i in range(sides):
            c0, s0, c1, s1 = math.cos(a[i]), math.sin(a[i]), math.cos(a[i + 1]), math.sin(a[i + 1])
            n0 = np.array([c0, dr, s0]) / math.hypot(1.0, dr)
            n1 = np.array([c1, dr, s1]) / math.hypot(1.0, dr)
            # counter-clockwise seen from outside: the angle runs from +X towards +Z
            p = [(r0 * c0, y0, r0 * s0), (r0 * c1, y0, r0 * s1),
                 (r1 * c1, y1, r1 * s1), (r1 * c0, y1, r1 * s0)]
            quad(material, p[::-1], [n0, n1, n1, n0][::-1], [y0, y0, y1, y1][::-1])
    for y, rr, ny in ((0.0, radius[0], -1.0), (ARM_LENGTH, radius[-1], 1.0)):
        pos, nrm, wts, idx = bands["arm_white"]
        centre = len(pos)
        pos.append((0.0, y, 0.0))
        pos.extend((rr * math.cos(x), y, rr * math.sin(x)) for x in a[:-1])
        nrm.extend([(0.0, ny, 0.0)] * (sides + 1))
        wts.extend([weights(y)] * (sides + 1))
        for i in range(sides):     # a fan; from +X towards +Z it faces -Y
            i0, i1 = centre + 1 + i, centre + 1 + (i + 1) % sides
            idx.extend([centre, i0, i1] if ny < 0 else [centre, i1, i0])
    return bands


def icosphere(radius: float, subdivisions: int = 1):
    """(positions, normals, indices) of an icosphere (smooth), built here for determinism."""
    g = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0), (0, -1, g), (0, 1, g), (0, -1, -g),
         (0, 1, -g), (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1)]
    verts = [np.array(p, np.float64) / np.linalg.norm(p) for p in v]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(subdivisions):
        mid: dict = {}

        def middle(i, j):
            key = (min(i, j), max(i, j))
            if key not in mid:
                m = verts[i] + verts[j]
                verts.append(m / np.linalg.norm(m))
                mid[key] = len(verts) - 1
            return mid[key]
        nf = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = nf
    n = np.array(verts)
    return n * radius, n, [i for f in faces for i in f]


# ---------------------------------------------------------------- the decal texture

def decal(width: int = 256, height: int = 64) -> np.ndarray:
    """(height, width, 3) uint8 sRGB, top row first: the rover's side panel, orange with a
    black-and-white chequered stripe along the bottom, hazard stripes at both ends and a
    white roundel with a black 7 in the middle."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    u, v = (x + 0.5) / width, (y + 0.5) / height
    img = np.empty((height, width, 3))
    img[:] = (235, 120, 30)
    chequer = (v > 0.8) & ((np.floor(u * 32) + np.floor((v - 0.8) * 10)) % 2 == 0)
    img[v > 0.8] = (245, 245, 240)
    img[chequer] = (20, 20, 22)
    ends = ((u < 0.1) | (u > 0.9)) & (v <= 0.8)
    hazard = np.floor((x + y) / 8.0) % 2 == 0
    img[ends & hazard] = (25, 25, 25)
    img[ends & ~hazard] = (250, 210, 20)
    # the roundel, circular on the panel (2.0 m x 0.4 m: a texel is 7.8 x 6.25 mm)
    cx, cy, r = 0.5, 0.42, 0.3
    px, py = (u - cx) * 2.0, (v - cy) * 0.4
    round_ = px * px + py * py < (r * 0.4) ** 2
    img[round_] = (245, 245, 240)
    # a 7: a top bar and a slanted stroke, in the roundel's pixel space
    lx, ly = px / 0.4 / r, (v - cy) / r                      # both ~[-1, 1] in the roundel
    bar = (ly > -0.62) & (ly < -0.38) & (lx > -0.42) & (lx < 0.48)
    stroke = (np.abs(lx - (0.42 - 0.5 * (ly + 0.5))) < 0.13) & (ly > -0.45) & (ly < 0.72)
    img[round_ & (bar | stroke)] = (15, 15, 18)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


def png_bytes(rgb: np.ndarray) -> bytes:
    """An 8-bit RGB PNG of `rgb`, its zlib stream written with stored deflate blocks (the
    bytes depend on the pixels only)."""
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[row].tobytes() for row in range(h))
    blocks = []
    for i in range(0, len(raw), 65535):
        chunk = raw[i:i + 65535]
        final = 1 if i + 65535 >= len(raw) else 0
        blocks.append(struct.pack("<BHH", final, len(chunk), len(chunk) ^ 0xFFFF) + chunk)
    stream = b"\x78\x01" + b"".join(blocks) + struct.pack(">I", zlib.adler32(raw))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data)))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", stream) + chunk(b"IEND", b""))


# ---------------------------------------------------------------- the glTF container

class Gltf:
    """A glTF document and its one binary buffer, built up part by part."""

    def __init__(self):
        self.doc = {"asset": {"version": "2.0", "generator": GENERATOR}, "scene": 0,
                    "scenes": [], "nodes": [], "meshes": [], "materials": [],
                    "textures": [], "images": [], "samplers": [], "skins": [],
                    "animations": [], "accessors": [], "bufferViews": [], "buffers": []}
        self.bin = bytearray()

    def view(self, data: bytes, target: int | None = None) -> int:
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target is not None:
            v["target"] = target
        self.bin.extend(data)
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, values, component: int, kind: str, target: int | None = None,
                 bounds: bool = False) -> int:
        dtype = {FLOAT: np.float32, UBYTE: np.uint8, USHORT: np.uint16, UINT: np.uint32}[component]
        a = np.ascontiguousarray(np.asarray(values), dtype=dtype)
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[kind]
        flat = a.reshape(-1, width)
        acc = {"bufferView": self.view(flat.astype(np.dtype(dtype).newbyteorder("<")).tobytes(), target),
               "componentType": component, "count": len(flat), "type": kind}
        if bounds:
            acc["min"] = [float(x) if component == FLOAT else int(x) for x in flat.min(0)]
            acc["max"] = [float(x) if component == FLOAT else int(x) for x in flat.max(0)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def add(self, key: str, item: dict) -> int:
        self.doc[key].append(item)
        return len(self.doc[key]) - 1

    def glb(self) -> bytes:
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["buffers"] = [{"byteLength": len(self.bin)}]
        js = json.dumps(self.doc, separators=(",", ":"), ensure_ascii=True).encode("ascii")
        js += b" " * (-len(js) % 4)
        total = 12 + 8 + len(js) + 8 + len(self.bin)
        return (struct.pack("<4sII", b"glTF", 2, total)
                + struct.pack("<I4s", len(js), b"JSON") + js
                + struct.pack("<I4s", len(self.bin), b"BIN\x00") + bytes(self.bin))


def rover() -> bytes:
    """The rover asset as .glb bytes."""
    g = Gltf()
    # materials: baseColorFactor is linear RGB (glTF)
    sampler = g.add("samplers", {"magFilter": LINEAR_FILTER, "minFilter": LINEAR_FILTER,
                                 "wrapS": REPEAT, "wrapT": REPEAT})
    image = g.add("images", {"bufferView": g.view(png_bytes(decal())), "mimeType": "image/png",
                             "name": "decal"})
    texture = g.add("textures", {"sampler": sampler, "source": image})
    colours = {"paint": (0.85, 0.25, 0.03), "glass": (0.05, 0.09, 0.16),
               "tyre": (0.035, 0.035, 0.04), "groove": (0.45, 0.45, 0.47),
               "hub_light": (0.9, 0.85, 0.75), "hub_dark": (0.12, 0.05, 0.02),
               "arm_red": (0.7, 0.04, 0.03), "arm_white": (0.85, 0.85, 0.82),
               "lamp": (1.0, 0.85, 0.3)}
    mat = {name: g.add("materials", {"name": name, "pbrMetallicRoughness": {
        "baseColorFactor": [*rgb, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.6}})
        for name, rgb in colours.items()}
    mat["decal"] = g.add("materials", {"name": "decal", "pbrMetallicRoughness": {
        "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "baseColorTexture": {"index": texture},
        "metallicFactor": 0.0, "roughnessFactor": 0.5}})

    def primitive(material: str, pos, nrm, idx, uv=None, joints=None, weights=None) -> dict:
        attrs = {"POSITION": g.accessor(to_asset(pos), FLOAT, "VEC3", ARRAY_BUFFER,
                                        bounds=True),
                 "NORMAL": g.accessor(to_asset(nrm), FLOAT, "VEC3", ARRAY_BUFFER)}
        if uv is not None:
            attrs["TEXCOORD_0"] = g.accessor(uv, FLOAT, "VEC2", ARRAY_BUFFER)
        if joints is not None:
            attrs["JOINTS_0"] = g.accessor(joints, UBYTE, "VEC4", ARRAY_BUFFER)
            attrs["WEIGHTS_0"] = g.accessor(weights, FLOAT, "VEC4", ARRAY_BUFFER)
        return {"attributes": attrs, "indices": g.accessor(idx, USHORT, "SCALAR",
                                                           ELEMENT_ARRAY_BUFFER),
                "material": mat[material], "mode": 4}

    chassis = box_faces(CHASSIS, uv_sides=True)
    cabin = box_faces(CABIN)
    body = g.add("meshes", {"name": "body", "primitives": [
        primitive("paint", *chassis["rest"]),
        primitive("decal", chassis["sides"][0], chassis["sides"][1], chassis["sides"][3],
                  uv=chassis["sides"][2]),
        primitive("glass", *cabin["rest"])]})
    wheel = g.add("meshes", {"name": "wheel", "primitives": [
        primitive(m, *p) for m, p in wheel_parts().items()]})
    lamp_p, lamp_n, lamp_i = icosphere(0.06, 1)
    lamp = g.add("meshes", {"name": "lamp", "primitives": [primitive("lamp", lamp_p, lamp_n,
                                                                     lamp_i)]})
    arm = g.add("meshes", {"name": "arm", "primitives": []})

    # nodes: the vehicle's tree first (its index 0), the skinned arm last
    nodes = g.doc["nodes"]

    def node(name: str, **fields) -> int:
        return g.add("nodes", {"name": name, **fields})

    vehicle = node("vehicle", children=[])
    kids = nodes[vehicle]["children"]
    kids.append(node("body", mesh=body, translation=to_asset(BODY_AT).tolist()))
    wheel_node, steer_node = {}, {}
    for name, (wx, wz) in wheel_offsets().items():
        centre = to_asset([wx, WHEEL_R, wz]).tolist()
        if name.startswith("wheel_f"):
            steer = steer_node[name] = node("steer_" + name[-2:], translation=centre,
                                            children=[])
            wheel_node[name] = node(name, mesh=wheel)
            nodes[steer]["children"].append(wheel_node[name])
            kids.append(steer)
        else:
            wheel_node[name] = node(name, mesh=wheel, translation=centre)
            kids.append(wheel_node[name])
    step = ARM_LENGTH / ARM_JOINTS
    joints = [node("arm_j0", translation=to_asset(ARM_BASE).tolist(), children=[])]
    kids.append(joints[0])
    for j in range(1, ARM_JOINTS):
        joints.append(node(f"arm_j{j}", translation=[0.0, step, 0.0], children=[]))
        nodes[joints[j - 1]]["children"].append(joints[j])
    tip = node("arm_tip", mesh=lamp, translation=[0.0, step, 0.0])
    nodes[joints[-1]]["children"].append(tip)

    # The skin's bind pose: the vehicle at its static (identity) pose, the joints straight
    # up. The tube's vertices are placed there, and inverseBindMatrices undo each joint's
    # world matrix in that pose.
    base = np.array(ARM_BASE)
    bind_worlds = [translate(to_asset(base + [0.0, j * step, 0.0])) for j in range(ARM_JOINTS)]
    ibm = np.stack([np.linalg.inv(m).T.reshape(16) for m in bind_worlds])   # column-major
    skin = g.add("skins", {"name": "arm", "joints": joints, "skeleton": joints[0],
                           "inverseBindMatrices": g.accessor(ibm, FLOAT, "MAT4")})
    for material, (pos, nrm, wts, idx) in tube().items():
        pos = np.asarray(pos) + base
        j = np.tile(np.array([0, 1, 2, 0], np.uint8), (len(pos), 1))
        g.doc["meshes"][arm]["primitives"].append(
            primitive(material, pos, nrm, idx, joints=j, weights=np.asarray(wts)))
    arm_node = node("arm", mesh=arm, skin=skin)
    g.add("scenes", {"name": "rover", "nodes": [vehicle, arm_node]})

    # animations: one shared key time accessor
    times = g.accessor(key_times(), FLOAT, "SCALAR", bounds=True)

    def animation(name: str, tracks: list[tuple[int, str, np.ndarray]]):
        samplers, channels = [], []
        for target, path, values in tracks:
            kind = "VEC4" if path == "rotation" else "VEC3"
            samplers.append({"input": times, "interpolation": "LINEAR",
                             "output": g.accessor(values, FLOAT, kind)})
            channels.append({"sampler": len(samplers) - 1,
                             "target": {"node": target, "path": path}})
        g.add("animations", {"name": name, "samplers": samplers, "channels": channels})

    d = drive()
    up = [0.0, 1.0, 0.0]
    # the path is in the scene's frame; the +Z-facing rover turns 90 degrees more to follow
    tracks = [(vehicle, "translation", d["position"]),
              (vehicle, "rotation", continuous(quat_axis(up, d["yaw"] + math.pi / 2.0)))]
    for name, steer in steer_node.items():
        tracks.append((steer, "rotation", continuous(quat_axis(up, d["steer_" + name[-2:]]))))
    for name, w in wheel_node.items():
        tracks.append((w, "rotation", continuous(quat_axis(AXLE, d["spin"][name]))))
    animation("drive", tracks)
    animation("swing", [(joints[i], "rotation", q) for i, q in
                        enumerate(swing().values())])
    return g.glb()


def check_keys(glb: bytes) -> None:
    """The generator's own guard: no two successive rotation keys 90 degrees or more apart
    (slerp takes the short way, so 180 would turn a wheel backwards; 90 leaves a margin)."""
    js_len = struct.unpack_from("<I", glb, 12)[0]
    doc = json.loads(glb[20:20 + js_len])
    binary = glb[20 + js_len + 8:]
    for anim in doc["animations"]:
        for ch in anim["channels"]:
            if ch["target"]["path"] != "rotation":
                continue
            acc = doc["accessors"][anim["samplers"][ch["sampler"]]["output"]]
            view = doc["bufferViews"][acc["bufferView"]]
            q = np.frombuffer(binary, np.float32, acc["count"] * 4,
                              view["byteOffset"]).reshape(-1, 4).astype(np.float64)
            angle = 2.0 * np.degrees(np.arccos(np.clip(np.abs(np.sum(q[1:] * q[:-1], 1)), 0, 1)))
            if angle.max() >= 90.0:
                raise AssertionError(f"{anim['name']}: node {ch['target']['node']} turns "
                                     f"{angle.max():.1f} degrees between two keys")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ASSETS, help="folder for rover.glb")
    args = ap.parse_args(argv)
    data = rover()
    check_keys(data)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "rover.glb").write_bytes(data)


if __name__ == "__main__":
    main()
