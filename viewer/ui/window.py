"""The GLFW window: an OpenGL 3.3 core context wrapped by ModernGL, and imgui drawn with
imgui-bundle's GLFW backend (which needs PyOpenGL).

Every input event, from GLFW or from a script, goes through `key_event` / `mouse_*` here:
imgui gets it at once, then the viewer's InputRouter queues it (see viewer/ui/input.py).
"""
from __future__ import annotations

import glfw  # before imgui_bundle: its backend imports glfw and PyOpenGL
import moderngl
from imgui_bundle import imgui
from imgui_bundle.python_backends.glfw_backend import GlfwRenderer

from world.errors import UserError
from .input import InputRouter

NO_DISPLAY = "no display: install xvfb and run under xvfb-run, or set DISPLAY"


class Window:
    def __init__(self, size: tuple[int, int], title: str, router: InputRouter):
        self.router = router
        self._glfw_errors: list[str] = []
        glfw.ERROR_REPORTING = "ignore"           # errors are collected by the callback below
        glfw.set_error_callback(lambda code, text: self._glfw_errors.append(
            text.decode(errors="replace") if isinstance(text, bytes) else str(text)))
        if not glfw.init():
            reason = self._glfw_errors[-1] if self._glfw_errors else ""
            raise UserError(NO_DISPLAY + (f" (GLFW: {reason})" if reason else ""))
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        glfw.window_hint(glfw.DOUBLEBUFFER, True)
        self.handle = glfw.create_window(int(size[0]), int(size[1]), title, None, None)
        if not self.handle:
            detail = "; ".join(self._glfw_errors[-1:]) or "unknown reason"
            glfw.terminate()
            raise UserError(f"cannot open a window with an OpenGL 3.3 core context ({detail})")
        glfw.make_context_current(self.handle)
        self.ctx = moderngl.create_context(require=330)
        imgui.create_context()
        imgui.get_io().set_ini_filename("")      # no imgui.ini left in the working folder
        self.gui = GlfwRenderer(self.handle, attach_callbacks=False)
        glfw.set_key_callback(self.handle, lambda w, key, sc, action, mods: self.key_event(key, action))
        glfw.set_char_callback(self.handle, lambda w, ch: self.gui.char_callback(w, ch))
        glfw.set_cursor_pos_callback(self.handle, lambda w, x, y: self.mouse_move(x, y))
        glfw.set_mouse_button_callback(
            self.handle, lambda w, b, action, mods: self.mouse_button(b, action == glfw.PRESS))
        glfw.set_scroll_callback(self.handle, lambda w, dx, dy: self.mouse_scroll(dx, dy))

    # -- input, real or scripted
    def key_event(self, key: int, action: int):
        self.gui.keyboard_callback(self.handle, key, 0, action, 0)
        self.router.key(key, action)

    def mouse_move(self, x: float, y: float):
        imgui.get_io().add_mouse_pos_event(float(x), float(y))
        self.router.move(x, y)

    def mouse_button(self, button: int, pressed: bool):
        if 0 <= button < 5:
            imgui.get_io().add_mouse_button_event(button, pressed)
        self.router.button(button, pressed)

    def mouse_scroll(self, dx: float, dy: float):
        imgui.get_io().add_mouse_wheel_event(float(dx), float(dy))
        self.router.scroll(dy)

    # -- frame
    @property
    def framebuffer_size(self) -> tuple[int, int]:
        return tuple(glfw.get_framebuffer_size(self.handle))

    @property
    def size(self) -> tuple[int, int]:
        return tuple(glfw.get_window_size(self.handle))

    def set_size(self, size: tuple[int, int]):
        glfw.set_window_size(self.handle, int(size[0]), int(size[1]))

    def should_close(self) -> bool:
        return bool(glfw.window_should_close(self.handle))

    def close(self):
        glfw.set_window_should_close(self.handle, True)

    def poll(self):
        glfw.poll_events()

    def begin_gui(self):
        self.gui.process_inputs()
        imgui.new_frame()

    def end_gui(self):
        imgui.render()
        self.ctx.screen.use()
        self.gui.render(imgui.get_draw_data())

    def swap(self):
        glfw.swap_buffers(self.handle)

    def release(self):
        self.gui.shutdown()
        imgui.destroy_context()
        glfw.destroy_window(self.handle)
        glfw.terminate()
