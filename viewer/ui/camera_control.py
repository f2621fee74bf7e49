"""Mouse and keyboard camera moves, made by changing the scene's CameraSpec (position and
look_at); the renderer's Camera reads the spec every frame, and a screenshot's sidecar
records it, so a moved view reproduces headless.

Screen conventions here are the mouse's: x to the right, y down, in window pixels.
"""
from __future__ import annotations

import copy
import math

import numpy as np

from world.scene import CameraSpec

ORBIT_RAD_PER_PX = 0.005
LOOK_RAD_PER_PX = 0.003
ZOOM_PER_STEP = 0.9            # distance factor per wheel notch
MIN_DISTANCE = 1e-3
POLE_MARGIN = 0.02             # radians kept between the view direction and the up axis


def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation of v about the unit axis."""
    axis = axis / np.linalg.norm(axis)
    c, s = math.cos(angle), math.sin(angle)
    return v * c + np.cross(axis, v) * s + axis * np.dot(axis, v) * (1.0 - c)


class CameraControl:
    def __init__(self, spec: CameraSpec, time=lambda: 0.0):
        """time: the shown frame's time; a keyed camera's first move leaves its keys for a
        still camera at the pose of that time (reset returns to the keys)."""
        self.spec = spec
        self.time = time
        self.home = copy.deepcopy(spec)

    def _free(self):
        self.spec.detach(self.time())

    # -- frame of the current view
    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(forward, right, true up) of the spec's view, unit vectors."""
        fwd = self.spec.look_at - self.spec.position
        fwd = fwd / np.linalg.norm(fwd)
        right = np.cross(fwd, self.spec.up)
        right /= np.linalg.norm(right)
        return fwd, right, np.cross(right, fwd)

    @property
    def distance(self) -> float:
        return float(np.linalg.norm(self.spec.look_at - self.spec.position))

    def _turn(self, offset: np.ndarray, yaw: float, elevate: float) -> np.ndarray:
        """Turn a vector about the up axis by `yaw`, then towards the up axis by `elevate`,
        keeping it POLE_MARGIN off the axis so the view never flips."""
        up = self.spec.up / np.linalg.norm(self.spec.up)
        offset = _rotate(offset, up, yaw)
        axis = np.cross(offset, up)
        if np.linalg.norm(axis) < 1e-12:
            return offset
        angle = math.acos(float(np.clip(np.dot(offset / np.linalg.norm(offset), up), -1.0, 1.0)))
        elevate = float(np.clip(elevate, angle - (math.pi - POLE_MARGIN), angle - POLE_MARGIN))
        return _rotate(offset, axis, elevate)

    # -- mouse
    def orbit(self, dx: float, dy: float):
        """Left drag: the eye circles the look-at point as if the scene were grabbed (drag
        right: it turns right; drag down: the eye rises and the view looks down on it)."""
        self._free()
        offset = self.spec.position - self.spec.look_at
        offset = self._turn(offset, -dx * ORBIT_RAD_PER_PX, dy * ORBIT_RAD_PER_PX)
        self.spec.position = self.spec.look_at + offset

    def look(self, dx: float, dy: float):
        """Fly-mode left drag: the view turns about the eye (drag right: look right)."""
        self._free()
        offset = self.spec.look_at - self.spec.position
        offset = self._turn(offset, -dx * LOOK_RAD_PER_PX, -dy * LOOK_RAD_PER_PX)
        self.spec.look_at = self.spec.position + offset

    def pan(self, dx: float, dy: float, viewport_height: int):
        """Right/middle drag: eye and look-at slide so the point at the look-at distance
        follows the mouse."""
        self._free()
        _, right, up = self.basis()
        per_px = 2.0 * self.distance * math.tan(math.radians(self.spec.fov_y) * 0.5) / max(viewport_height, 1)
        move = (-dx * right + dy * up) * per_px
        self.spec.position = self.spec.position + move
        self.spec.look_at = self.spec.look_at + move

    def zoom(self, steps: float):
        """Wheel: each notch forward brings the eye 10% closer to the look-at point."""
        self._free()
        offset = self.spec.position - self.spec.look_at
        n = float(np.linalg.norm(offset))
        factor = max(ZOOM_PER_STEP ** steps, MIN_DISTANCE / max(n, 1e-300))
        self.spec.position = self.spec.look_at + offset * factor

    # -- keyboard
    def fly(self, forward: float, right: float, upward: float, seconds: float):
        """WASD/QE: move eye and look-at together; speed scales with the look-at distance
        (one distance in two seconds) so small and large scenes both feel usable."""
        self._free()
        fwd, r, _ = self.basis()
        up = self.spec.up / np.linalg.norm(self.spec.up)
        speed = max(self.distance, 0.1) * 0.5
        move = (fwd * forward + r * right + up * upward) * speed * seconds
        self.spec.position = self.spec.position + move
        self.spec.look_at = self.spec.look_at + move

    def reset(self):
        for key, value in vars(copy.deepcopy(self.home)).items():
            setattr(self.spec, key, value)
