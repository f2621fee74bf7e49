"""Input routing: imgui first, the camera and the viewer's keys only when imgui does not
want the event.

GLFW callbacks (and the script runner, which feeds the same events) give every event to
imgui at once and queue it here; `dispatch` runs after `imgui.new_frame()`, when
io.want_capture_mouse / want_capture_keyboard describe this frame, and sends what imgui
did not take to the camera or a key action. A drag that started over the scene keeps
moving the camera even if the cursor passes over the panel, and one that started over the
panel never does.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import glfw

from .camera_control import CameraControl

FLY_KEYS = {  # key: (forward, right, up)
    glfw.KEY_W: (1, 0, 0), glfw.KEY_S: (-1, 0, 0),
    glfw.KEY_D: (0, 1, 0), glfw.KEY_A: (0, -1, 0),
    glfw.KEY_E: (0, 0, 1), glfw.KEY_Q: (0, 0, -1),
}


@dataclass
class InputRouter:
    camera: Callable[[], CameraControl]            # the current scene's camera control
    viewport_height: Callable[[], int]
    actions: dict[int, Callable[[], None]] = field(default_factory=dict)   # key -> action
    fly_look: bool = False                          # left drag turns the view, not orbits
    queue: list = field(default_factory=list)
    held: set = field(default_factory=set)
    tapped: set = field(default_factory=set)        # pressed and released within a frame
    drag: int | None = None                          # mouse button of a drag over the scene
    cursor: tuple[float, float] = (0.0, 0.0)

    # -- events, in the order they arrived
    def key(self, key: int, action: int):
        self.queue.append(("key", key, action))

    def button(self, button: int, pressed: bool):
        self.queue.append(("button", button, pressed))

    def move(self, x: float, y: float):
        self.queue.append(("move", float(x), float(y)))

    def scroll(self, dy: float):
        self.queue.append(("scroll", float(dy)))

    def dispatch(self, want_mouse: bool, want_keyboard: bool, seconds: float):
        events, self.queue = self.queue, []
        for ev in events:
            getattr(self, "_" + ev[0])(want_mouse, want_keyboard, *ev[1:])
        self._fly(seconds)

    def _key(self, want_mouse, want_keyboard, key, action):
        if action == glfw.RELEASE:
            if key in self.held:
                self.held.discard(key)
            return
        if want_keyboard:
            return
        if key in FLY_KEYS:
            if action == glfw.PRESS:
                self.held.add(key)
                self.tapped.add(key)
        elif action == glfw.PRESS and key in self.actions:
            self.actions[key]()

    def _button(self, want_mouse, want_keyboard, button, pressed):
        if not pressed:
            if button == self.drag:
                self.drag = None
        elif self.drag is None and not want_mouse:
            self.drag = button

    def _move(self, want_mouse, want_keyboard, x, y):
        dx, dy = x - self.cursor[0], y - self.cursor[1]
        self.cursor = (x, y)
        cam = self.camera()
        if self.drag == glfw.MOUSE_BUTTON_LEFT:
            (cam.look if self.fly_look else cam.orbit)(dx, dy)
        elif self.drag in (glfw.MOUSE_BUTTON_RIGHT, glfw.MOUSE_BUTTON_MIDDLE):
            cam.pan(dx, dy, self.viewport_height())

    def _scroll(self, want_mouse, want_keyboard, dy):
        if not want_mouse:
            self.camera().zoom(dy)

    def _fly(self, seconds: float):
        keys = self.held | self.tapped
        self.tapped = set()
        if not keys:
            return
        f = sum(FLY_KEYS[k][0] for k in keys)
        r = sum(FLY_KEYS[k][1] for k in keys)
        u = sum(FLY_KEYS[k][2] for k in keys)
        if f or r or u:
            self.camera().fly(f, r, u, seconds)
