"""Screenshots: the rendered image with the `hmblur shot` sidecar (so `hmblur shot SCENE
--params FILE.json --mode M` reproduces it), and the window's own pixels (panel included)."""
from __future__ import annotations

import os
from pathlib import Path

import moderngl
import numpy as np

from viewer.cli.args import Setup
from viewer.io.sidecar import sidecar
from world.conventions import to_image
from viewer.io.imageio import OutputSet, linear_to_srgb8
from ..render.renderer import Renderer


def next_path(folder: Path, stem: str) -> Path:
    """folder/stem_NNN.png with the first number whose .png and .json (the sidecar) are
    both free: a screenshot only takes names where nothing is."""
    k = 0
    while any(os.path.lexists(folder / f"{stem}_{k:03d}{suffix}") for suffix in (".png", ".json")):
        k += 1
    return folder / f"{stem}_{k:03d}.png"


def save_shot(path: Path, renderer: Renderer, mode: str, s: Setup, scene_arg: str,
              extra: dict | None = None) -> Path:
    """Render `mode` as `hmblur shot` does (full quality, one call: a reference is all its
    sub-frames, whatever the progressive view has reached) and write PNG + sidecar."""
    result = renderer.render(mode, s.time, s.params, seed=s.seed)
    side = sidecar(s, mode, result, renderer.ctx, scene_arg)
    if extra:
        side["viewer"] = extra
    files = OutputSet()                  # the image and its sidecar together, or neither
    files.png(path, linear_to_srgb8(result.image))
    files.json(path.with_suffix(".json"), side)
    files.commit()
    return path


def grab_window(ctx: moderngl.Context, size: tuple[int, int]) -> np.ndarray:
    """The default framebuffer's back buffer as uint8 RGB, top row first (call before the
    swap). Reading the screen leaves a GL error behind on some drivers: cleared here."""
    w, h = size
    data = ctx.screen.read(viewport=(0, 0, w, h), components=3, alignment=1)
    _ = ctx.error
    return to_image(np.frombuffer(data, np.uint8).reshape(h, w, 3))
