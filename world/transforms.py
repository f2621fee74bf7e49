"""4x4 and 3x3 transforms in the column-vector convention (p' = M @ p).

pyrr builds the camera matrices; it uses row vectors (translation in the last row), so
every pyrr matrix is transposed here, and only here. pyrr returns garbage for integer
input: everything is converted to float64 first. Tests check each against numpy.
"""
from __future__ import annotations

import numpy as np
import pyrr


def _f64(v) -> np.ndarray:
    return np.asarray(v, dtype=np.float64)


def _undecorated(f):
    """pyrr's argument-converting decorator inspects the function's signature on every
    call; the arguments here are float64 arrays already, so the function beneath it is
    called."""
    return getattr(f, "__wrapped__", f)


_axis_rotation = _undecorated(pyrr.matrix33.create_from_axis_rotation)
_look_at = _undecorated(pyrr.matrix44.create_look_at)
_perspective = _undecorated(pyrr.matrix44.create_perspective_projection)


def translate(t) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = _f64(t)
    return m


def scale(s) -> np.ndarray:
    return np.diag(np.append(_f64(s) * np.ones(3), 1.0))


def axis_angle(w) -> np.ndarray:
    """3x3 rotation by angle |w| about w/|w| (identity for w = 0): the scene format's Rot(w)."""
    w = _f64(w)
    theta = float(np.linalg.norm(w))
    if theta == 0.0:
        return np.eye(3)
    return _axis_rotation(w / theta, theta, dtype=np.float64).T.copy()


def axis_angles(w: np.ndarray) -> np.ndarray:
    """axis_angle of each row of w (n, 3): (n, 3, 3), by Rodrigues' formula."""
    w = np.asarray(w, np.float64)
    theta = np.linalg.norm(w, axis=1)
    axis = w / np.where(theta > 0.0, theta, 1.0)[:, None]
    k = np.zeros((len(w), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = axis[:, 2], -axis[:, 1], axis[:, 0]
    s, c = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def euler_xyz_degrees(deg) -> np.ndarray:
    """R0 = Rz @ Ry @ Rx from Euler angles in degrees (X applied first)."""
    rx, ry, rz = np.radians(_f64(deg))
    return axis_angle([0, 0, rz]) @ axis_angle([0, ry, 0]) @ axis_angle([rx, 0, 0])


def homogeneous(r3: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = r3
    return m


def look_at(eye, forward, up) -> np.ndarray:
    """World-to-view matrix: the camera at `eye` looking along `forward` (OpenGL: -Z)."""
    eye = _f64(eye)
    return _look_at(eye, eye + _f64(forward), _f64(up), dtype=np.float64).T.copy()


def perspective(fov_y_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """OpenGL perspective projection (clip z in [-w, w] between near and far)."""
    return _perspective(
        float(fov_y_deg), float(aspect), float(near), float(far), dtype=np.float64).T.copy()


# Largest entry of a normal matrix handed on: the shaders take it as float32 and dot
# normals with themselves (1e15^2 is far below float32's 3e38).
NORMAL_MATRIX_MAX = 1e15


def normal_matrix(m4: np.ndarray) -> np.ndarray:
    """Inverse transpose of the upper 3x3: how normals go to world space. Where the 3x3 is
    singular or nearly so (a keyed scale passing through zero), its limit: the cofactor
    matrix (det * inverse transpose, defined at det = 0) signed by det and scaled to a
    largest entry of 1: the same directions, which are normalised after (a flattened
    object's normals all become its plane's)."""
    m3 = _f64(m4)[:3, :3]
    with np.errstate(all="ignore"):
        try:
            n = np.linalg.inv(m3).T
        except np.linalg.LinAlgError:
            n = None
        if n is not None and np.all(np.abs(n) <= NORMAL_MATRIX_MAX):
            return n
        return cofactor_direction(m3)


# A singular pose's thinnest extent, for the ray tracer (which needs an inverse): this
# fraction of its largest, at least LIMIT_MIN_EXTENT (a scale of exactly 0 on every axis).
LIMIT_THICKNESS = 1e-6
LIMIT_MIN_EXTENT = 1e-9
# Inverse entries up to this are taken as they are (float32 holds them).
INVERSE_MAX = 1e30


def limit_inverse(m4: np.ndarray) -> np.ndarray:
    """The inverse of an affine 4x4; where it is singular or its inverse leaves float32
    (a keyed scale through zero), the inverse of its limit: each singular value of the
    3x3 raised to LIMIT_THICKNESS of the largest (at least LIMIT_MIN_EXTENT), so a
    flattened object is a sheet that thin, as the rasteriser draws it with none."""
    m4 = _f64(m4)
    with np.errstate(all="ignore"):
        try:
            inv = np.linalg.inv(m4)
        except np.linalg.LinAlgError:
            inv = None
        if inv is not None and np.all(np.abs(inv) <= INVERSE_MAX):
            return inv
        u, s, vt = np.linalg.svd(np.nan_to_num(m4[:3, :3]))
        s = np.maximum(s, max(LIMIT_THICKNESS * float(s.max()), LIMIT_MIN_EXTENT))
        out = np.eye(4)
        out[:3, :3] = (vt.T / s) @ u.T
        out[:3, 3] = -out[:3, :3] @ m4[:3, 3]
        return out


def cofactor_direction(m3: np.ndarray) -> np.ndarray:
    """sign(det) * cofactor(m3), scaled to a largest entry of 1 (zeros for a 3x3 of rank
    below 2, whose normals are undefined: such an object covers no area)."""
    peak = float(np.max(np.abs(m3)))
    if not (np.isfinite(peak) and peak > 0.0):
        return np.zeros((3, 3))
    a = m3 / peak                                # cof(k a) = k^2 cof(a): direction kept
    c = np.cross(a[[1, 2, 0]], a[[2, 0, 1]])     # row i: a[i+1] x a[i+2], the cofactors
    det = float(a[0] @ c[0])
    c = -c if det < 0.0 else c
    big = float(np.max(np.abs(c)))
    return c / big if big > 0.0 else np.zeros((3, 3))


# ---------------------------------------------------------------- unit quaternions
# (w, x, y, z), the rotation q v q*: the project's one order. Keyed rotations (scene format
# v1.1) and glTF's rotations (stored (x, y, z, w); world/gltf/reader.py reorders them as it
# reads them) are slerped and made matrices as these.

def quat_axis(axis: int, angle: float) -> np.ndarray:
    """The rotation by `angle` radians about coordinate axis 0, 1 or 2."""
    q = np.zeros(4)
    q[0] = np.cos(0.5 * angle)
    q[1 + axis] = np.sin(0.5 * angle)
    return q


def quat_mul(a, b) -> np.ndarray:
    """The Hamilton product a b: the rotation b, then a."""
    aw, ax, ay, az = _f64(a)
    bw, bx, by, bz = _f64(b)
    return np.array([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw])


def quat_euler_xyz_degrees(deg) -> np.ndarray:
    """R0 = Rz @ Ry @ Rx (euler_xyz_degrees) as a unit quaternion qz qy qx."""
    rx, ry, rz = np.radians(_f64(deg))
    return quat_mul(quat_axis(2, rz), quat_mul(quat_axis(1, ry), quat_axis(0, rx)))


def quat_normalised(q) -> np.ndarray:
    """Quaternions (..., 4) divided by their length; the identity where the length is 0 or
    not finite."""
    q = _f64(q)
    n = np.sqrt(np.einsum("...i,...i->...", q, q))[..., None]
    good = (n > 0.0) & np.isfinite(n)
    return np.where(good, q / np.where(good, n, 1.0), [1.0, 0.0, 0.0, 0.0])


def quat_matrix(q) -> np.ndarray:
    """3x3 rotations (..., 3, 3) of unit quaternions (..., 4) = (w, x, y, z)."""
    q = _f64(q)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r = np.empty(q.shape[:-1] + (3, 3))
    r[..., 0, 0] = 1 - 2 * (y * y + z * z)
    r[..., 0, 1] = 2 * (x * y - w * z)
    r[..., 0, 2] = 2 * (x * z + w * y)
    r[..., 1, 0] = 2 * (x * y + w * z)
    r[..., 1, 1] = 1 - 2 * (x * x + z * z)
    r[..., 1, 2] = 2 * (y * z - w * x)
    r[..., 2, 0] = 2 * (x * z - w * y)
    r[..., 2, 1] = 2 * (y * z + w * x)
    r[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def trs(t, q, s) -> np.ndarray:
    """T(t) @ R(q) @ S(s), (..., 4, 4), of translations (..., 3), unit quaternions (..., 4)
    and scale factors (..., 3)."""
    t, s = _f64(t), _f64(s)
    m = np.zeros(t.shape[:-1] + (4, 4))
    m[..., :3, :3] = quat_matrix(q) * s[..., None, :]    # R @ diag(s): column k scaled by s[k]
    m[..., :3, 3] = t
    m[..., 3, 3] = 1.0
    return m


SLERP_MIN_ANGLE = 1e-6     # below it, slerp's 1 / sin(theta) is replaced by a normalised lerp


def slerp(q0, q1, u: float) -> np.ndarray:
    """Shortest-arc spherical interpolation of unit quaternions (u = 0: q0, u = 1: q1):
    q1 is negated where q0 . q1 < 0, then (sin((1-u) th) q0 + sin(u th) q1) / sin th with
    cos th = q0 . q1; normalised q0 + u (q1 - q0) where th < SLERP_MIN_ANGLE."""
    q0, q1 = _f64(q0), _f64(q1)
    d = float(q0 @ q1)
    if d < 0.0:
        q1, d = -q1, -d
    theta = float(np.arccos(min(d, 1.0)))
    if theta < SLERP_MIN_ANGLE:
        q = q0 + u * (q1 - q0)
        return q / np.linalg.norm(q)
    return (np.sin((1.0 - u) * theta) * q0 + np.sin(u * theta) * q1) / np.sin(theta)


def euler_xyz_degrees_of(r3: np.ndarray) -> np.ndarray:
    """Euler degrees (x, y, z) with euler_xyz_degrees(result) = r3 (a rotation matrix)."""
    r3 = _f64(r3)
    ry = -np.arcsin(np.clip(r3[2, 0], -1.0, 1.0))
    if abs(r3[2, 0]) < 1.0 - 1e-12:
        rx, rz = np.arctan2(r3[2, 1], r3[2, 2]), np.arctan2(r3[1, 0], r3[0, 0])
    else:                                   # gimbal lock: the x and z turns share one axis
        rx, rz = np.arctan2(-r3[1, 2], r3[1, 1]), 0.0
    return np.degrees([rx, ry, rz])


def box_corners(vertices: np.ndarray) -> np.ndarray:
    """(8, 3) corners of the axis-aligned box around `vertices`, corner i taking hi on
    axis k where bit k of i is set."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    return np.array([[(lo, hi)[i >> k & 1][k] for k in range(3)] for i in range(8)])
