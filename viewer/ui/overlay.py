"""The frame-time overlay: fps, a frame-time graph, milliseconds per pass (and how they were
measured) and whatever counters the mode reported in RenderResult.stats.

Three levels, cycled by the O key: "full" (everything; kept inside the window, scrolled by
the mouse wheel over it when it is taller), "compact" (fps, the graph, the passes' total
and the hybrid's ray count: a few lines, the default in windows under COMPACT_BELOW px
tall) and "off"."""
from __future__ import annotations

import numpy as np
from imgui_bundle import imgui

from viewer.render.timing import describe

HISTORY = 120
GRAPH_WIDTH = 220
COMPACT_GRAPH = (150, 28)
MARGIN = 8                       # px between the overlay and the window's edges
LEVELS = ("full", "compact", "off")
COMPACT_BELOW = 600              # window height (px) below which the overlay starts compact
COMPACT_STATS = ("masked_pixels", "rays")


def initial_level(window_height: int) -> str:
    return "compact" if window_height < COMPACT_BELOW else "full"


def next_level(level: str) -> str:
    return LEVELS[(LEVELS.index(level) + 1) % len(LEVELS)]


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
                 device: str, window_size: tuple[int, int], left: float = 0.0,
                 level: str = "full") -> tuple[float, float, float, float] | None:
    """Draw at the window's top right, right of x = `left` (the panel's edge) and inside
    the window; returns its rectangle (x, y, w, h) in window pixels, None when off.
    Each pass: its time, and the main thread's CPU time in it (host work)."""
    if level == "off":
        return None
    width, height = window_size
    imgui.set_next_window_pos(imgui.ImVec2(width - MARGIN, MARGIN), imgui.Cond_.always,
                              imgui.ImVec2(1.0, 0.0))     # pivot: the top-right corner
    imgui.set_next_window_size_constraints(
        imgui.ImVec2(0.0, 0.0),
        imgui.ImVec2(max(1.0, width - left - 2 * MARGIN), max(1.0, height - 2 * MARGIN)))
    imgui.set_next_window_bg_alpha(0.65)
    flags = (imgui.WindowFlags_.no_title_bar | imgui.WindowFlags_.no_resize
             | imgui.WindowFlags_.no_collapse | imgui.WindowFlags_.no_saved_settings
             | imgui.WindowFlags_.no_focus_on_appearing | imgui.WindowFlags_.no_nav
             | imgui.WindowFlags_.no_move | imgui.WindowFlags_.always_auto_resize)
    if level == "compact":
        # A few lines always fit: the mouse passes through to the scene.
        flags |= imgui.WindowFlags_.no_inputs | imgui.WindowFlags_.no_scrollbar
    imgui.begin("##overlay", None, flags)
    recent = times.recent()
    last = float(recent[-1]) if len(recent) else 0.0
    imgui.text(f"{times.fps:5.1f} fps   {last:6.1f} ms/frame")
    graph = COMPACT_GRAPH if level == "compact" else (GRAPH_WIDTH, 48)
    if len(recent):
        imgui.plot_lines("##frametimes", recent, 0, f"max {recent.max():.1f} ms", 0.0,
                         max(float(recent.max()) * 1.1, 1.0), imgui.ImVec2(*graph))
    total = sum(pass_ms.values()) if pass_ms else None
    host = sum(pass_cpu_ms.values()) if pass_cpu_ms else None
    if level == "compact":
        if total is not None:
            imgui.text(f"passes {total:.2f} ms" + (f", host {host:.2f}" if host is not None else ""))
        shown = [f"{k} {format_stat(stats[k])}" for k in COMPACT_STATS if k in stats]
        if shown:
            imgui.text(", ".join(shown))
        imgui.text_disabled("O: hide, then full")
    else:
        imgui.text(f"timing: {describe(method)}")
        if method == "cpu":
            imgui.text_disabled("(software GL: timer queries untrusted)")
        if pass_ms:
            imgui.text_disabled(f"{'pass':<22s}{'ms':>8s}{'host':>8s}")
        for name, ms in pass_ms.items():
            imgui.text(f"{name:<22s}{ms:8.2f}{cpu_text(pass_cpu_ms.get(name))}")
        if pass_ms:
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
