"""The frame-time overlay: fps, a frame-time graph, milliseconds per pass (and how they were
measured) and whatever counters the mode reported in RenderResult.stats."""
from __future__ import annotations

import numpy as np
from imgui_bundle import imgui

from ..render.timing import describe

HISTORY = 120
GRAPH_WIDTH = 220


class FrameTimes:
    """The last HISTORY frame times in milliseconds, oldest first."""

    def __init__(self, n: int = HISTORY):
        self.values = np.zeros(n, np.float32)
        self.count = 0

    def add(self, ms: float):
        self.values = np.roll(self.values, -1)
        self.values[-1] = ms
        self.count += 1

    def recent(self) -> np.ndarray:
        return self.values[-min(self.count, len(self.values)):] if self.count else self.values[:0]

    @property
    def fps(self) -> float:
        r = self.recent()
        return 1000.0 / float(r.mean()) if len(r) and r.mean() > 0 else 0.0


def format_stat(value) -> str:
    if isinstance(value, float):
        return f"{value:.3g}"
    return str(value)


def cpu_text(ms) -> str:
    """A pass's host CPU column: 8 characters, blank where it was not measured."""
    return f"{ms:8.2f}" if ms is not None else " " * 8


def draw_overlay(times: FrameTimes, pass_ms: dict, pass_cpu_ms: dict, stats: dict, method: str,
                 device: str, window_width: int) -> tuple[float, float, float, float]:
    """Draw at the window's top right; returns its rectangle (x, y, w, h) in window pixels.
    Each pass: its time, and the main thread's CPU time in it (host work)."""
    imgui.set_next_window_pos(imgui.ImVec2(window_width - 8, 8), imgui.Cond_.always,
                              imgui.ImVec2(1.0, 0.0))     # pivot: the top-right corner
    imgui.set_next_window_bg_alpha(0.65)
    flags = (imgui.WindowFlags_.no_decoration | imgui.WindowFlags_.no_saved_settings
             | imgui.WindowFlags_.no_focus_on_appearing | imgui.WindowFlags_.no_nav
             | imgui.WindowFlags_.no_move | imgui.WindowFlags_.always_auto_resize
             | imgui.WindowFlags_.no_inputs)      # the mouse passes through to the scene
    imgui.begin("##overlay", None, flags)
    recent = times.recent()
    last = float(recent[-1]) if len(recent) else 0.0
    imgui.text(f"{times.fps:5.1f} fps   {last:6.1f} ms/frame")
    if len(recent):
        imgui.plot_lines("##frametimes", recent, 0, f"max {recent.max():.1f} ms", 0.0,
                         max(float(recent.max()) * 1.1, 1.0), imgui.ImVec2(GRAPH_WIDTH, 48))
    imgui.text(f"timing: {describe(method)}")
    if method == "cpu":
        imgui.text_disabled("(software GL: timer queries untrusted)")
    if pass_ms:
        imgui.text_disabled(f"{'pass':<22s}{'ms':>8s}{'host':>8s}")
    for name, ms in pass_ms.items():
        imgui.text(f"{name:<22s}{ms:8.2f}{cpu_text(pass_cpu_ms.get(name))}")
    if pass_ms:
        total, host = sum(pass_ms.values()), sum(pass_cpu_ms.values()) if pass_cpu_ms else None
        imgui.text(f"{'passes':<22s}{total:8.2f}{cpu_text(host)}")
    if stats:
        imgui.separator()
        for name, value in stats.items():
            imgui.text(f"{name:<22s}{format_stat(value):>8s}")
    imgui.separator()
    imgui.text_disabled(device)
    pos, size = imgui.get_window_pos(), imgui.get_window_size()
    imgui.end()
    return (pos.x, pos.y, size.x, size.y)
