"""One camera for the rasteriser and the ray tracer: GL matrices and pixel-centre rays."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import transforms as tf
from .conventions import pixel_centres_ndc
from .scene import CameraSpec


@dataclass
class Camera:
    spec: CameraSpec
    width: int
    height: int

    @property
    def aspect(self) -> float:
        return self.width / self.height

    def view(self, t: float) -> np.ndarray:
        """World-to-view at time t (a read-only array: the same pose gives the same one,
        kept, because building it costs ~0.1 ms and a frame asks for it several times)."""
        eye, fwd, up = self.spec.pose(t)
        key = np.concatenate([eye, fwd, up]).tobytes()
        views = self.__dict__.setdefault("_views", {})
        v = views.get(key)
        if v is None:
            if len(views) >= 8:
                views.clear()
            v = views[key] = tf.look_at(eye, fwd, up)
            v.flags.writeable = False
        return v

    def projection(self) -> np.ndarray:
        s = self.spec
        return tf.perspective(s.fov_y, self.aspect, s.near, s.far)

    def view_projection(self, t: float) -> np.ndarray:
        return self.projection() @ self.view(t)

    def eye(self, t: float) -> np.ndarray:
        return self.spec.pose(t)[0]

    def rays(self, t: float, i, j) -> tuple[np.ndarray, np.ndarray]:
        """Origins and unit directions of the rays through the centres of image pixels (i, j).
        The origins are one read-only row, the eye, broadcast to (n, 3) (stride 0: the
        ray caster sees at once that they are shared).

        A camera seen at the same pose twice in a row (a still camera, frame after frame)
        keeps every pixel's direction and answers by lookup; the values are the same."""
        eye, fwd, up = self.spec.pose(t)
        pose = (np.concatenate([eye, fwd, up]).tobytes(), self.spec.fov_y, self.width,
                self.height)
        cache = self.__dict__.setdefault("_ray_cache", {})
        if cache.get("pose") == pose:
            if "grid" not in cache:
                jj, ii = np.mgrid[0:self.height, 0:self.width]
                cache["grid"] = self._directions(eye, fwd, up, ii.ravel(), jj.ravel())
            # np.take: several times faster than fancy indexing for rows of (N, 3).
            d = np.take(cache["grid"], np.asarray(j) * self.width + np.asarray(i), axis=0)
        else:
            cache.clear()
            cache["pose"] = pose
            d = self._directions(eye, fwd, up, i, j)
        return np.broadcast_to(np.asarray(eye, np.float64), d.shape), d

    def _directions(self, eye, fwd, up, i, j) -> np.ndarray:
        right = np.cross(fwd, up)
        right /= np.linalg.norm(right)
        true_up = np.cross(right, fwd)
        x, y = pixel_centres_ndc(i, j, self.width, self.height)
        tan_half = np.tan(np.radians(self.spec.fov_y) * 0.5)
        sx, sy = x * (tan_half * self.aspect), y * tan_half
        # Column by column: (n, 3) broadcasting costs several times more here.
        d = np.empty((len(sx), 3))
        for k in range(3):
            d[:, k] = fwd[k] + sx * right[k] + sy * true_up[k]
        inv_len = 1.0 / np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
        d *= inv_len[:, None]
        return d

    def project(self, t: float, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World points -> (GL window pixel coordinates x right / y up, view depth)."""
        p = np.c_[np.asarray(points, dtype=np.float64), np.ones(len(points))]
        view = p @ self.view(t).T
        clip = view @ self.projection().T
        ndc = clip[:, :2] / clip[:, 3:4]
        win = (ndc * 0.5 + 0.5) * np.array([self.width, self.height])
        return win, -view[:, 2]
