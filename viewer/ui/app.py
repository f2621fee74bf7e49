"""The interactive viewer: a GLFW window over the same render core as the CLI.

Each frame: poll input (and due script actions) -> imgui new frame -> input imgui did not
want goes to the camera and keys -> render the mode into the pool (progressively for an
accumulating mode) -> draw the chosen buffer into the window through the debug view ->
panel and overlay -> swap. A failure while loading a scene or rendering (a shader error,
say) is shown in the panel and the window stays open.
"""
from __future__ import annotations

import sys
import time as _time
from dataclasses import dataclass
from pathlib import Path

import glfw  # noqa: F401  (before imgui_bundle, see viewer/ui/window.py)
from imgui_bundle import imgui

from viewer.cli.args import Setup, parse_float, parse_int, parse_seed, parse_size, parse_time
from world.errors import UserError, printable
from viewer.glcontext import device_name
from viewer.io.imageio import write_json_atomic, write_png_atomic
from viewer.render.passes.debug_view import KINDS, DebugView
from viewer.render.modes import MODES
from viewer.render.renderer import Renderer
from world.loader import load_scene
from viewer.ui import capture
from viewer.ui.camera_control import CameraControl
from viewer.ui.input import InputRouter
from viewer.ui.overlay import FrameTimes, draw_overlay, initial_level, next_level
from viewer.ui.panel import draw_panel
from viewer.ui.progressive import Progressive, accumulating_pass
from viewer.ui.script import Action, Timeline
from viewer.ui.state import FIXED_STEP, ViewState
from viewer.render.timing import PassClock
from viewer.ui.window import Window

RSS_MARK_FRAME = 50


@dataclass
class RunOptions:
    frames: int | None = None            # exit after this many frames
    screenshot: Path | None = None       # the window's contents at the last frame
    stats_json: Path | None = None
    shot_dir: Path = Path(".")
    script: list[Action] = ()
    record: str | None = None            # record from the first frame to this video path
    record_fps: float = 30.0


def rss_kb() -> int:
    """Resident set size of this process (Linux), in KiB; 0 where unknown."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


class App:
    def __init__(self, setup: Setup, scene_arg: str, mode: str, options: RunOptions):
        self.options = options
        self.state = ViewState(scene_arg, setup.scene, mode, setup.time, setup.params, setup.seed,
                               scene_text=scene_arg, overlay=initial_level(setup.size[1]),
                               animations=dict(setup.animations or {}))
        self.camera = CameraControl(setup.scene.camera, lambda: self.state.time)
        self.router = InputRouter(lambda: self.camera, lambda: self.window.size[1])
        self.router.actions.update({
            glfw.KEY_F12: self.screenshot, glfw.KEY_P: self.screenshot,
            glfw.KEY_SPACE: self.toggle_play, glfw.KEY_R: self.camera_reset,
            glfw.KEY_F: self.toggle_fly, glfw.KEY_H: self.toggle_panel,
            glfw.KEY_V: self.toggle_record,
            glfw.KEY_O: self.cycle_overlay,
            glfw.KEY_ESCAPE: lambda: self.window.close(),
        })
        self.window = Window(setup.size, f"hmblur view - {setup.scene.name}", self.router)
        self.ctx = self.window.ctx
        self.device = device_name(self.ctx)
        self.renderer = Renderer(self.ctx, setup.scene, self.window.framebuffer_size)
        self.debug = DebugView(self.renderer.programs)
        self.clock = PassClock(self.ctx)
        self.progressive = Progressive()
        self.timeline = Timeline(options.script)
        self.times = FrameTimes()
        self.pass_ms: dict = {}
        self.pass_cpu_ms: dict = {}           # the main thread's CPU time in each pass
        self.stats: dict = {}
        self.shown_name = self.shown_kind = ""
        self.panel_rect = self.overlay_rect = (0.0, 0.0, 0.0, 0.0)
        self.panel_sections: dict = {}        # section -> (top, bottom) y in the window
        self.script_failure: str | None = None      # the first scripted action that failed
        self.rss: list[tuple[int, int]] = []
        self.frame_index = 0
        self.recorder = None

    # -- actions (panel, keys, script)
    def set_mode(self, mode: str):
        if mode not in MODES:
            self.state.report(f"mode {mode}: expected one of {', '.join(MODES)}")
            return
        self.state.mode = mode

    def set_view(self, name: str):
        self.state.buffer = "" if name in ("", "output") else name

    def toggle_play(self):
        self.state.playing = not self.state.playing

    def toggle_fly(self):
        self.router.fly_look = not self.router.fly_look

    def toggle_panel(self):
        self.state.show_panel = not self.state.show_panel

    def cycle_overlay(self):
        self.state.overlay = next_level(self.state.overlay)

    def camera_reset(self):
        self.camera.reset()

    def is_progressive(self) -> bool:
        try:
            pipe = self.renderer.pipeline(self.state.mode, self.state.params)
            return accumulating_pass(pipe) is not None
        except Exception:  # a mode that fails to build is reported when rendered
            return False

    def output_name(self) -> str:
        try:
            return self.renderer.output_name(self.state.mode)
        except Exception:
            return "?"

    def buffer_names(self) -> tuple[list[str], list[str]]:
        """Pool textures the current mode writes (pipeline order), and the others still
        held from modes shown earlier."""
        pool = set(self.renderer.pool.names())
        try:
            passes = self.renderer.pipeline(self.state.mode, self.state.params).passes
        except Exception:
            passes = []
        current = list(dict.fromkeys(n for p in passes for n in p.produces if n in pool))
        return current, [n for n in self.renderer.pool.names() if n not in current]

    def open_scene(self, source: str):
        """Load another scene; on failure keep the current one and show why."""
        source = source.strip()
        try:
            scene = load_scene(source)
            renderer = Renderer(self.ctx, scene, self.renderer.size)
        except Exception as exc:             # a bad file, a scene the GPU cannot hold
            self.state.report(f"open {source!r}: {exc}")
            return
        self.renderer.release()
        self.renderer, self.debug = renderer, DebugView(renderer.programs)
        s = self.state
        s.scene, s.scene_arg, s.scene_text, s.time = scene, source, source, scene.render.time
        s.buffer, s.error, s.animations = "", "", {}
        self.camera = CameraControl(scene.camera, lambda: self.state.time)
        self.progressive.reset()
        glfw.set_window_title(self.window.handle, f"hmblur view - {scene.name}")

    def choose_animation(self, entry: str, choice):
        """Play `choice` ("all", "none", an animation's name or index) on the gltf entry
        `entry`: the scene is loaded again with that choice (what moves, and so what the
        renderer keeps still, follows from it); the view and time stay."""
        s = self.state
        chosen = {**s.animations, entry: choice}
        try:
            scene = load_scene(s.scene_arg, chosen)
            scene.camera = s.scene.camera
            renderer = Renderer(self.ctx, scene, self.renderer.size)
        except Exception as exc:             # an unknown entry or animation
            s.report(f"animation {entry} {choice}: {exc}")
            return
        self.renderer.release()
        self.renderer, self.debug = renderer, DebugView(renderer.programs)
        s.scene, s.animations = scene, chosen
        self.progressive.reset()

    def setup(self) -> Setup:
        s = self.state
        return Setup(s.scene, self.renderer.size, s.time, s.params, s.seed,
                     animations=dict(s.animations) or None)

    def screenshot(self):
        s = self.state
        folder = self.options.shot_dir
        path = capture.next_path(folder, f"{s.scene.name}_{s.mode}")
        try:
            capture.save_shot(path, self.renderer, s.mode, self.setup(), s.scene_arg,
                              {"params": s.params.to_dict(), "buffer": s.buffer or "output"})
        except Exception as exc:
            s.report(f"screenshot {path}: {exc}")
            return
        s.shots.append(str(path))
        print(f"{path}: {s.mode} {self.renderer.size[0]}x{self.renderer.size[1]} t={s.time:g}")

    def toggle_record(self, path=None):
        """Start recording the shown image (viewer/ui/record.py), or stop and write it."""
        from viewer.ui.record import Recorder, next_path
        s = self.state
        if self.recorder is not None:
            rec, self.recorder = self.recorder, None
            try:
                written = rec.stop()
            except Exception as exc:
                s.report(f"recording {rec.out.video}: {exc}")
                return
            if written is not None:
                s.shots.append(str(written))
                print(f"{written}: {rec.writer.count} frames at {rec.fps:g} fps")
            return
        path = path or next_path(self.options.shot_dir, f"{s.scene.name}_{s.mode}")
        try:
            self.recorder = Recorder.open(str(path), self.options.record_fps, s,
                                          self.window.framebuffer_size)
        except Exception as exc:
            s.report(f"record {path}: {exc}")

    def record_frame(self):
        grab = capture.grab_window(self.ctx, self.window.framebuffer_size)
        if not self.recorder.add(grab, self.state.time):
            self.state.report("recording stopped: the window changed size")
            self.toggle_record()

    def perform(self, a: Action):
        """One script action (viewer/ui/script.py)."""
        s, args = self.state, a.args
        try:
            if a.name == "mode":
                self.set_mode(args[0])
            elif a.name == "set":
                s.params.apply([args[0]])
            elif a.name == "key":
                key = getattr(glfw, f"KEY_{args[0].upper()}", None)
                if key is None:
                    a.fail("a GLFW key name (P, F12, SPACE, W, ...)")
                self.window.key_event(key, glfw.PRESS)
                self.timeline.at(self.frame_index + 1, lambda: self.window.key_event(key, glfw.RELEASE))
            elif a.name == "resize":
                self.window.set_size(parse_size(args[0]))
            elif a.name in ("orbit", "pan"):
                button = glfw.MOUSE_BUTTON_LEFT if a.name == "orbit" else glfw.MOUSE_BUTTON_RIGHT
                x0, y0 = self.scene_centre()
                dx, dy = parse_float("dx", args[0]), parse_float("dy", args[1])
                self.drag(button, x0, y0, x0 + dx, y0 + dy)
            elif a.name == "drag":
                buttons = {"left": glfw.MOUSE_BUTTON_LEFT, "right": glfw.MOUSE_BUTTON_RIGHT,
                           "middle": glfw.MOUSE_BUTTON_MIDDLE}
                if args[0] not in buttons:
                    a.fail("button left, right or middle")
                self.drag(buttons[args[0]], *(parse_float("coordinate", v) for v in args[1:]))
            elif a.name == "zoom":
                notches = parse_float("zoom", args[0])
                x0, y0 = self.scene_centre()
                self.window.mouse_move(x0, y0)
                self.timeline.at(self.frame_index + 1, lambda: self.window.mouse_scroll(0.0, notches))
            elif a.name == "view":
                self.set_view(args[0])
            elif a.name == "visual":
                if args[0] not in ("auto",) + KINDS:
                    a.fail("auto or one of " + ", ".join(KINDS))
                s.view.kind = args[0]
            elif a.name == "time":
                s.time = parse_time("time", args[0])
            elif a.name in ("play", "pause"):
                s.playing = a.name == "play"
            elif a.name == "speed":
                s.speed = parse_float("speed", args[0])
            elif a.name == "shutter":
                s.scene.camera.shutter = max(0.0, parse_float("shutter", args[0]))
            elif a.name == "seed":
                s.seed = parse_seed("seed", args[0])
            elif a.name == "open":
                self.open_scene(args[0])
            elif a.name == "animation":
                choice = args[1]
                self.choose_animation(args[0], int(choice) if choice.isdigit() else choice)
            elif a.name == "reset":
                self.camera.reset()
            elif a.name in ("fly", "panel"):
                if args[0] not in ("on", "off"):
                    a.fail("on or off")
                if a.name == "fly":
                    self.router.fly_look = args[0] == "on"
                else:
                    s.show_panel = args[0] == "on"
            elif a.name == "overlay":
                s.overlay = args[0]
            elif a.name == "subframes":
                s.sub_frames = parse_int("subframes", args[0], 1, 4096)
            elif a.name == "quit":
                self.window.close()
        except UserError as exc:
            s.report(f"--script {a.where}: {str(exc).removeprefix(f'--script {a.where}: ')}")

    def scene_centre(self) -> tuple[float, float]:
        """The middle of the part of the window the panel does not cover."""
        w, h = self.window.size
        left = self.panel_rect[2] if self.state.show_panel else 0.0
        return ((left + w) / 2.0, h / 2.0)

    def drag(self, button: int, x0: float, y0: float, x1: float, y1: float):
        """A mouse drag spread over four frames, as a hand would make it."""
        w = self.window
        n = self.frame_index
        w.mouse_move(x0, y0)
        self.timeline.at(n + 1, lambda: w.mouse_button(button, True))
        self.timeline.at(n + 2, lambda: w.mouse_move(x1, y1))
        self.timeline.at(n + 3, lambda: w.mouse_button(button, False))

    # -- the frame
    def advance(self, seconds: float):
        if self.state.playing:
            self.state.time += seconds * self.state.speed

    def render_scene(self):
        s = self.state
        size = self.window.framebuffer_size
        if size[0] < 1 or size[1] < 1:              # minimised
            return
        if size != self.renderer.size:
            self.renderer.resize(size)              # the pool reallocates on next use
        screen = self.ctx.screen
        try:
            if self.is_progressive():
                frame = self.progressive.step(self.clock, self.renderer, s.mode, s.time, s.params,
                                              s.seed, s.image_key(size), s.sub_frames)
            else:
                frame = self.clock.render(self.renderer, s.mode, s.time, s.params, s.seed)
            self.pass_ms, self.stats = dict(frame.pass_ms), dict(frame.stats)
            self.pass_cpu_ms = dict(frame.pass_cpu_ms)
            output = self.renderer.output_name(s.mode)
            name = s.buffer if s.buffer in self.renderer.pool.names() else output
            s.view.gain = self.progressive.gain if (name == output and self.is_progressive()) else 1.0
            screen.use()
            screen.viewport = (0, 0) + size
            screen.clear(0.1, 0.1, 0.1, 1.0)
            self.shown_kind = self.debug.draw(screen, self.renderer.pool, name, s.view, (0, 0) + size)
            self.shown_name = name
        except Exception as exc:      # a shader error, a failing pass: show it, keep going
            if f"{exc}" not in " ".join(s.errors):
                print(printable(f"hmblur view: {exc.__class__.__name__}: {exc}"), file=sys.stderr)
            s.report(f"render {s.mode}: {exc}")
            self.progressive.reset()
            screen.use()
            screen.viewport = (0, 0) + size
            screen.clear(0.25, 0.05, 0.05, 1.0)

    def run(self) -> int:
        opts = self.options
        fixed = opts.frames is not None              # scripted runs step time by a fixed amount
        last = _time.perf_counter()
        grab = None
        if opts.record is not None:
            self.toggle_record(opts.record)
        while not self.window.should_close():
            if opts.frames is not None and self.frame_index >= opts.frames:
                break
            self.window.poll()
            for item in self.timeline.due(self.frame_index):
                if callable(item):
                    item()
                    continue
                errors = len(self.state.errors)
                self.perform(item)
                if len(self.state.errors) > errors and self.script_failure is None:
                    err = self.state.errors[-1]
                    self.script_failure = (err if err.startswith("--script ")
                                           else f"--script {item.where}: {err}")
            now = _time.perf_counter()
            seconds = FIXED_STEP if fixed else now - last
            if self.recorder is not None:       # recordings play at the scene's speed
                seconds = self.recorder.step
            if self.frame_index:
                self.times.add((now - last) * 1e3)
            last = now
            self.window.begin_gui()
            io = imgui.get_io()
            self.router.dispatch(io.want_capture_mouse, io.want_capture_keyboard, seconds)
            self.advance(seconds)
            self.render_scene()
            if self.recorder is not None:
                self.record_frame()
            if self.state.show_panel:
                self.panel_rect = draw_panel(self)
            left = self.panel_rect[0] + self.panel_rect[2] if self.state.show_panel else 0.0
            self.overlay_rect = draw_overlay(self.times, self.pass_ms, self.pass_cpu_ms,
                                             self.stats, self.clock.method,
                                             self.ctx.info["GL_RENDERER"], self.window.size,
                                             left, self.state.overlay)
            self.window.end_gui()
            self.frame_index += 1
            if opts.screenshot is not None and self.frame_index == opts.frames:
                grab = capture.grab_window(self.ctx, self.window.framebuffer_size)
            if self.frame_index == RSS_MARK_FRAME or self.frame_index % 25 == 0:
                self.rss.append((self.frame_index, rss_kb()))
            self.window.swap()
        self.rss.append((self.frame_index, rss_kb()))
        if self.recorder is not None:
            self.toggle_record()
        if grab is not None:
            write_png_atomic(opts.screenshot, grab)
        if opts.stats_json is not None:
            write_json_atomic(opts.stats_json, self.summary())
        if self.script_failure is not None:     # a scripted run that went wrong: exit 2
            raise UserError(self.script_failure)
        return 0

    def summary(self) -> dict:
        s = self.state
        return {
            "frames": self.frame_index, "mode": s.mode, "scene": s.scene_arg,
            "size": list(self.renderer.size), "window": list(self.window.size),
            "fps": self.times.fps, "frame_ms": self.times.recent().tolist(),
            "timing": self.clock.method, "device": self.device,
            "pass_ms": self.pass_ms, "pass_cpu_ms": self.pass_cpu_ms, "stats": self.stats,
            "rss_kb": self.rss, "errors": s.errors, "screenshots": s.shots,
            "panel_rect": list(self.panel_rect) if s.show_panel else None,
            "panel_sections": {k: list(v) for k, v in self.panel_sections.items()}
            if s.show_panel else None,
            "animations": s.animations,
            "overlay_rect": list(self.overlay_rect) if self.overlay_rect else None,
            "overlay": s.overlay,
            "camera": {k: list(map(float, v)) for k, v in
                       (("position", s.scene.camera.position), ("look_at", s.scene.camera.look_at))},
            "shown": {"buffer": self.shown_name, "visual": self.shown_kind},
            "progressive": {"done": self.progressive.done, "total": self.progressive.total},
        }

    def release(self):
        if self.recorder is not None:          # an error on the way: no half-written video
            self.recorder.abort()
        self.renderer.release()
        self.window.release()
