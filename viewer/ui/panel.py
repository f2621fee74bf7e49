"""The control panel: scene, mode, the current mode's parameters (generated from the
dataclasses), buffer view, animation, camera, screenshot, errors. Built from MODES,
MODE_GROUPS and the pool's names, so new modes and buffers appear without changes here."""
from __future__ import annotations

from typing import Protocol

from imgui_bundle import imgui

from viewer.render.passes.debug_view import KINDS
from ..render.modes import MODE_GROUPS, MODES
from world.asset_scene import animation_range
from world.loader import builtin_scene_names
from .camera_control import CameraControl
from .input import InputRouter
from .param_widgets import group_widgets
from .progressive import Progressive
from .state import ViewState
from .window import Window


class PanelHost(Protocol):
    """What the panel reads and calls on the viewer (viewer.ui.app.App), which imports this
    module: the panel never imports the app."""
    state: ViewState
    window: Window
    camera: CameraControl
    router: InputRouter
    progressive: Progressive
    recorder: object | None                 # the open recording, if any
    shown_name: str
    shown_kind: str
    panel_sections: dict

    def choose_animation(self, entry: str, choice): ...

    def screenshot(self): ...
    def toggle_record(self, path=None): ...
    def open_scene(self, source: str): ...
    def set_mode(self, mode: str): ...
    def set_view(self, name: str): ...
    def is_progressive(self) -> bool: ...
    def output_name(self) -> str: ...
    def buffer_names(self) -> tuple[list[str], list[str]]: ...

MAX_WIDTH = 320              # px, at window widths from 1280
MIN_WIDTH = 190              # px: narrower and the widgets lose their labels
WIDTH_FRACTION = 0.25        # of the window width in between
KEYS_HELP = ("left drag: orbit (fly look: turn); right/middle drag: pan; wheel: zoom; "
             "WASD QE: fly; space: play/pause; R: reset view; F: fly look; H: panel; "
             "O: overlay full/compact/off; P or F12: screenshot; V: record; Esc: quit")
ERROR_COLOUR = imgui.ImVec4(1.0, 0.45, 0.4, 1.0)
SHUTTER_MAX = 0.25
VISUALS = ("auto",) + KINDS


def panel_width(window_width: int) -> int:
    """A quarter of the window, within MIN_WIDTH .. MAX_WIDTH (never over a third of a
    window 570 px or wider)."""
    return int(min(MAX_WIDTH, max(MIN_WIDTH, round(WIDTH_FRACTION * window_width))))


def draw_panel(app: PanelHost) -> tuple[float, float, float, float]:
    """Draw the panel along the window's left edge (collapsible by its title bar's arrow,
    hidden by H); returns its rectangle (x, y, w, h)."""
    s = app.state
    window_width, height = app.window.size
    width = panel_width(window_width)
    imgui.set_next_window_pos(imgui.ImVec2(0, 0), imgui.Cond_.always)
    imgui.set_next_window_size(imgui.ImVec2(width, height), imgui.Cond_.always)
    imgui.set_next_window_bg_alpha(0.85)
    flags = imgui.WindowFlags_.no_move | imgui.WindowFlags_.no_resize | imgui.WindowFlags_.no_saved_settings
    imgui.begin("hmblur view", None, flags)
    imgui.push_item_width(-round(0.375 * width))      # the rest for the labels
    _errors(app)
    _scene(app)
    _mode(app)
    # Short sections first, so that the animation and buffer view stay above the fold of a
    # 720 px window; a mode's parameters (the hybrid's run to ~40 rows) come after them.
    app.panel_sections = {}
    for title, draw in (("Animation", _animation), ("Buffer view", _buffers),
                        ("Parameters", _parameters), ("Camera", _camera)):
        top = imgui.get_cursor_screen_pos().y
        if imgui.collapsing_header(title, imgui.TreeNodeFlags_.default_open):
            draw(app)
        app.panel_sections[title] = (top, imgui.get_cursor_screen_pos().y)
    imgui.separator()
    if imgui.button("Screenshot (F12 / P)"):
        app.screenshot()
    if imgui.button("Stop recording (V)" if app.recorder else "Record (V)"):
        app.toggle_record()
    if s.shots:
        imgui.text_wrapped(f"saved {s.shots[-1]}")
    imgui.pop_item_width()
    pos, size = imgui.get_window_pos(), imgui.get_window_size()
    imgui.end()
    return (pos.x, pos.y, size.x, size.y)


def _parameters(app):
    s = app.state
    groups = MODE_GROUPS.get(s.mode, ())
    if not groups:
        imgui.text_disabled(f"mode {s.mode} has no parameters")
    for g in groups:
        imgui.separator_text(g)
        for err in group_widgets(s.params, g):
            s.report(err)


def _errors(app):
    s = app.state
    if not s.error:
        return
    imgui.push_style_color(imgui.Col_.text, ERROR_COLOUR)
    imgui.text_wrapped(s.error)
    imgui.pop_style_color()
    if imgui.small_button("dismiss"):
        s.error = ""
    imgui.separator()


def _scene(app):
    s = app.state
    imgui.text(f"scene: {s.scene.name}")
    _, s.scene_text = imgui.input_text("##scene", s.scene_text)
    imgui.same_line()
    if imgui.button("Open"):
        app.open_scene(s.scene_text)
    names = builtin_scene_names()
    if names:
        current = names.index(s.scene_arg) if s.scene_arg in names else -1
        changed, idx = imgui.combo("built-in", current, names)
        if changed and idx != current:
            app.open_scene(names[idx])


def _mode(app):
    s = app.state
    modes = list(MODES)
    changed, idx = imgui.combo("mode", modes.index(s.mode) if s.mode in modes else 0, modes)
    if changed:
        app.set_mode(modes[idx])
    if app.is_progressive():
        p = app.progressive
        frac = p.done / p.total if p.total else 0.0
        imgui.progress_bar(frac, imgui.ImVec2(-1, 0), f"{p.done} / {p.total} sub-frames")
        changed, n = imgui.slider_int("sub-frames/frame", s.sub_frames, 1, 32)
        if changed:
            s.sub_frames = n
        imgui.set_item_tooltip("sub-frames added per displayed frame; the sum restarts "
                               "whenever anything changes")


def _buffers(app):
    s = app.state
    output = app.output_name()
    current, others = app.buffer_names()
    names = [""] + current + others
    labels = ([f"output ({output})"] + current
              + [f"{n} (earlier mode)" for n in others])    # still in the pool, not redrawn
    current = names.index(s.buffer) if s.buffer in names else 0
    changed, idx = imgui.combo("buffer", current, labels)
    if changed:
        app.set_view(names[idx])
    changed, k = imgui.combo("visual", VISUALS.index(s.view.kind), list(VISUALS))
    if changed:
        s.view.kind = VISUALS[k]
    if app.shown_kind:
        imgui.text_disabled(f"showing {app.shown_name} as {app.shown_kind}")


def _animation(app):
    s = app.state
    if imgui.button("Pause" if s.playing else "Play"):
        s.playing = not s.playing
    imgui.same_line()
    if imgui.button("|<"):
        s.time = s.scene.render.time
    imgui.same_line()
    if imgui.button("-1"):
        s.time -= 1.0 / 60.0
    imgui.same_line()
    if imgui.button("+1"):
        s.time += 1.0 / 60.0
    imgui.set_item_tooltip("step one 60 Hz frame")
    # Assign only on a change: imgui hands back float32, and merely drawing the panel must
    # not round the time a screenshot's sidecar records.
    changed, t = imgui.drag_float("time (s)", s.time, 0.002, 0.0, 0.0, "%.4f")
    if changed:
        s.time = float(t)
    changed, speed = imgui.slider_float("speed", s.speed, -2.0, 2.0, "%.2f")
    if changed:
        s.speed = float(speed)
    cam = s.scene.camera
    changed, shutter = imgui.slider_float("shutter (s)", float(cam.shutter), 0.0, SHUTTER_MAX, "%.4f")
    if changed:
        cam.shutter = max(0.0, float(shutter))
    changed, seed = imgui.input_int("seed", s.seed)
    if changed:
        s.seed = max(0, int(seed))
    for inst, line in zip(s.scene.assets, animation_lines(s.scene)):
        imgui.text_wrapped(line)
        labels, values = animation_choices(inst)
        if len(values) > 2:                      # more than "all" and "none"
            current = chosen_index(inst, values, s.animations.get(inst.name))
            changed, idx = imgui.combo(f"plays##{inst.name}", current, labels)
            if changed and idx != current:
                app.choose_animation(inst.name, values[idx])


def animation_choices(inst) -> tuple[list[str], list]:
    """What a gltf entry can play, as the panel lists it and as the scene file's
    `animation` names it: all, each animation (by name, by index where it has none or
    shares it), none."""
    anims = inst.asset.animations
    names = [a.name for a in anims]
    labels, values = ["all"], ["all"]
    for i, name in enumerate(names):
        unique = bool(name) and names.count(name) == 1 and name not in ("all", "none")
        labels.append(name if unique else f"#{i} {name or ''}".rstrip())
        values.append(name if unique else i)
    return labels + ["none"], values + ["none"]


def chosen_index(inst, values: list, chosen) -> int:
    """The entry's current choice among `values`: the one made in the viewer, else what
    it plays (every animation: all; none; one)."""
    if chosen in values:
        return values.index(chosen)
    played = tuple(inst.animations)
    if played == tuple(range(len(values) - 2)):
        return 0
    if not played:
        return len(values) - 1
    return 1 + played[0]


def animation_lines(scene) -> list[str]:
    """One line per glTF entry: each of its asset's animations with its key range in
    scene time, "(not played)" where the entry does not play it, "(looped)" where it
    loops."""
    lines = []
    for inst in scene.assets:
        names = []
        for i, anim in enumerate(inst.asset.animations):
            label = anim.name or f"#{i}"
            if i not in inst.animations:
                names.append(f"{label} (not played)")
                continue
            a0, a1 = animation_range(inst, (i,))
            names.append(f"{label} {a0:.2f}-{a1:.2f} s")
        text = ", ".join(names) if names else "no animations"
        lines.append(f"{inst.name}: {text}" + (" (looped)" if inst.loop and names else ""))
    return lines


def _camera(app):
    s = app.state
    changed, fly = imgui.checkbox("fly look (F)", app.router.fly_look)
    if changed:
        app.router.fly_look = fly
    imgui.same_line()
    if imgui.button("Reset view (R)"):
        app.camera.reset()
    cam = s.scene.camera
    if cam.keys is not None:
        eye, fwd, _ = cam.pose(s.time)
        imgui.text_disabled(f"keyed path, {len(cam.keys.times)} keys (a move leaves it)")
        imgui.text_disabled("eye  " + " ".join(f"{x:.2f}" for x in eye))
        imgui.text_disabled("fwd  " + " ".join(f"{x:.2f}" for x in fwd))
    else:
        imgui.text_disabled("eye  " + " ".join(f"{x:.2f}" for x in cam.position))
        imgui.text_disabled("look " + " ".join(f"{x:.2f}" for x in cam.look_at))
    imgui.text_wrapped(KEYS_HELP)
