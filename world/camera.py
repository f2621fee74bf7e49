"""One camera for the rasteriser and the ray tracer: GL matrices and pixel-centre rays."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from world import transforms as tf
from world.conventions import pixel_centres_ndc
from world.scene import CameraSpec


@dataclass
class Camera:
    spec: CameraSpec
    width: int
    height: int
    # What is kept between calls: view matrices by pose (the last 8), the projection and
    # the pixel-centre rows and columns by the values they were made from.
    _views: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    _projection: tuple | None = field(default=None, init=False, repr=False, compare=False)
    _lens_cache: tuple | None = field(default=None, init=False, repr=False, compare=False)

    @property
    def aspect(self) -> float:
        return self.width / self.height

    def view(self, t: float) -> np.ndarray:
        """World-to-view at time t (a read-only array: the same pose gives the same one,
        kept, as a frame asks for it several times)."""
        eye, fwd, up = self.spec.pose(t)
        key = np.concatenate([eye, fwd, up]).tobytes()
        views = self._views
        v = views.get(key)
        if v is None:
            if len(views) >= 8:          # the oldest goes (a moving camera's frame asks
                views.pop(next(iter(views)))   # for t and the shutter's ends, and again)
            v = views[key] = tf.look_at(eye, fwd, up)
            v.flags.writeable = False
        return v

    def projection(self) -> np.ndarray:
        """The perspective projection (read-only, kept while the lens and size hold)."""
        s = self.spec
        key = (s.fov_y, self.aspect, s.near, s.far)
        if self._projection is None or self._projection[0] != key:
            p = tf.perspective(*key)
            p.flags.writeable = False
            self._projection = (key, p)
        return self._projection[1]

    def view_projection(self, t: float) -> np.ndarray:
        return self.projection() @ self.view(t)

    def eye(self, t: float) -> np.ndarray:
        return self.spec.pose(t)[0]

    def rays(self, t: float, i, j) -> tuple[np.ndarray, np.ndarray]:
        """Origins and unit directions of the rays through the centres of image pixels (i, j).
        The origins are one read-only row, the eye, broadcast to (n, 3) (stride 0: the
        ray caster sees at once that they are shared)."""
        eye, fwd, up = self.spec.pose(t)
        # Every column's and row's pixel-centre NDC (the convention's one place), then one
        # compiled pass over the rays, which also makes the camera's basis.
        cols, rows, scale_y = self._lens()
        d = _directions(np.asarray(i, np.int64).reshape(-1), np.asarray(j, np.int64).reshape(-1),
                        cols, rows, np.asarray(fwd, np.float64), np.asarray(up, np.float64),
                        scale_y * self.aspect, scale_y)
        # (np.broadcast_to's result, built directly; read-only like the eye)
        eye = np.ascontiguousarray(eye, np.float64)
        if eye.flags.writeable:
            eye = eye.copy()
            eye.flags.writeable = False
        return np.ndarray(d.shape, np.float64, buffer=eye, strides=(0, 8)), d

    def _lens(self) -> tuple[np.ndarray, np.ndarray, float]:
        """The pixel centres' NDC x of every column and y of every row, and tan(fov_y / 2),
        kept while the size and the field of view hold."""
        key = (self.width, self.height, self.spec.fov_y)
        if self._lens_cache is None or self._lens_cache[0] != key:
            x, _ = pixel_centres_ndc(np.arange(self.width), np.zeros(self.width),
                                     self.width, self.height)
            _, y = pixel_centres_ndc(np.zeros(self.height), np.arange(self.height),
                                     self.width, self.height)
            self._lens_cache = (key, (x, y, float(np.tan(np.radians(self.spec.fov_y) * 0.5))))
        return self._lens_cache[1]

    def project(self, t: float, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World points -> (GL window pixel coordinates x right / y up, view depth)."""
        p = np.c_[np.asarray(points, dtype=np.float64), np.ones(len(points))]
        view = p @ self.view(t).T
        clip = view @ self.projection().T
        ndc = clip[:, :2] / clip[:, 3:4]
        win = (ndc * 0.5 + 0.5) * np.array([self.width, self.height])
        return win, -view[:, 2]


@njit(cache=True, nogil=True)
def _directions(i, j, cols, rows, fwd, up, scale_x, scale_y):
    """Unit directions fwd + x sx right + y sy up' through pixels (i, j), x = cols[i] and
    y = rows[j] their centres in NDC, right = fwd x up normalised, up' = right x fwd (in
    numpy's order of operations: np.cross, and right / sqrt(right . right))."""
    right = np.empty(3)
    right[0] = fwd[1] * up[2] - fwd[2] * up[1]
    right[1] = fwd[2] * up[0] - fwd[0] * up[2]
    right[2] = fwd[0] * up[1] - fwd[1] * up[0]
    norm = np.sqrt(right[0] * right[0] + right[1] * right[1] + right[2] * right[2])
    for c in range(3):
        right[c] /= norm
    true_up = np.empty(3)
    true_up[0] = right[1] * fwd[2] - right[2] * fwd[1]
    true_up[1] = right[2] * fwd[0] - right[0] * fwd[2]
    true_up[2] = right[0] * fwd[1] - right[1] * fwd[0]
    n = i.shape[0]
    d = np.empty((n, 3))
    for k in range(n):
        sx = cols[i[k]] * scale_x
        sy = rows[j[k]] * scale_y
        for c in range(3):
            d[k, c] = fwd[c] + sx * right[c] + sy * true_up[c]
        inv_len = 1.0 / np.sqrt(d[k, 0] * d[k, 0] + d[k, 1] * d[k, 1] + d[k, 2] * d[k, 2])
        for c in range(3):
            d[k, c] *= inv_len
    return d
