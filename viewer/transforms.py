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
    call (~8-30 us, a moving object's matrices ask three times a frame); the arguments
    here are float64 arrays already, so the function beneath it is called."""
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
    """3x3 rotation by angle |w| about w/|w| (identity for w = 0): SCENE_FORMAT's Rot(w)."""
    w = _f64(w)
    theta = float(np.linalg.norm(w))
    if theta == 0.0:
        return np.eye(3)
    return _axis_rotation(w / theta, theta, dtype=np.float64).T.copy()


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


def normal_matrix(m4: np.ndarray) -> np.ndarray:
    """Inverse transpose of the upper 3x3: how normals go to world space."""
    return np.linalg.inv(m4[:3, :3]).T
