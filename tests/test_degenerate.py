"""Degenerate content in every mode: nothing crashes, nothing goes NaN, and the limits each
method promises hold."""
import textwrap

import numpy as np
import pytest

from world.errors import UserError
from viewer.render.graph.params import ParamSet
from viewer.render.modes import MODES
from viewer.render.renderer import Renderer
from world.loader import load_scene

ALL = sorted(MODES)
REALTIME = [m for m in ALL if m not in ("off", "reference")]


def scene(tmp_path, body, camera_extra="", head=""):
    p = tmp_path / "s.toml"
    p.write_text(textwrap.dedent(head) + textwrap.dedent(f"""
        background = [0.2, 0.3, 0.4]
        ambient = [0.3, 0.3, 0.3]
        [camera]
        position = [0.0, 0.0, 4.0]
        look_at = [0.0, 0.0, 0.0]
        fov_y = 45.0
        shutter = 0.05
        {camera_extra}
        [[lights]]
        direction = [0.0, -1.0, -1.0]
    """) + textwrap.dedent(body))
    return load_scene(p)


WALL = """
    [[objects]]
    mesh = { box = [20.0, 20.0, 0.1] }
    position = [0.0, 0.0, -2.0]
    material = { albedo = [0.9, 0.9, 0.9], texture = { kind = "stripes", axis = 0, size = 0.25, albedo2 = [0.1, 0.1, 0.1] } }
"""


def render_all(ctx, sc, size, modes=ALL, t=0.0, params=None):
    params = params or ParamSet()
    params.set("reference.samples", 8)
    r = Renderer(ctx, sc, size)
    try:
        return {m: r.render(m, t, params).image for m in modes}
    finally:
        r.release()


def test_empty_scene_is_the_background_in_every_mode(ctx, tmp_path):
    sc = scene(tmp_path, "")
    for mode, img in render_all(ctx, sc, (24, 16)).items():
        assert np.allclose(img, [0.2, 0.3, 0.4]), mode


def test_zero_area_triangles_render_finite(ctx, tmp_path):
    obj = tmp_path / "degenerate.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 2 0\nv 3 3 0\nv 4 4 0\n"
                   "f 1 2 3\nf 4 5 6\nf 1 1 2\n")
    sc = scene(tmp_path, WALL + f"""
        [[objects]]
        mesh = "{obj}"
        velocity = [5.0, 0.0, 0.0]
    """)
    for mode, img in render_all(ctx, sc, (40, 30)).items():
        assert np.all(np.isfinite(img)), mode


@pytest.mark.parametrize("size", [(1, 1), (37, 23), (3, 50)])
def test_odd_sizes_run_in_every_mode(ctx, tmp_path, size):
    sc = scene(tmp_path, WALL + """
        [[objects]]
        mesh = { sphere = { radius = 0.5, subdivisions = 2 } }
        velocity = [6.0, 0.0, 0.0]
    """)
    for mode, img in render_all(ctx, sc, size).items():
        assert img.shape == (size[1], size[0], 3), mode
        assert np.all(np.isfinite(img)), mode


def test_objects_behind_and_through_the_camera(ctx, tmp_path):
    sc = scene(tmp_path, WALL + """
        [[objects]]
        mesh = { box = [1.0, 1.0, 1.0] }
        position = [0.0, 0.0, 6.0]
        [[objects]]
        mesh = { box = [2.0, 2.0, 0.2] }
        position = [0.0, 0.0, 3.0]
        velocity = [0.0, 0.0, 40.0]
    """)
    for mode, img in render_all(ctx, sc, (48, 32)).items():
        assert np.all(np.isfinite(img)), mode


def test_shutter_zero_makes_every_mode_equal_off_exactly(ctx, tmp_path):
    sc = scene(tmp_path, WALL + """
        [[objects]]
        mesh = { sphere = { radius = 0.6, subdivisions = 2 } }
        velocity = [30.0, 0.0, 0.0]
        angular_velocity = [0.0, 9.0, 0.0]
    """, camera_extra="velocity = [2.0, 0.0, 0.0]")
    sc.camera.shutter = 0.0
    images = render_all(ctx, sc, (48, 32), t=0.01)
    for mode, img in images.items():
        assert img.tobytes() == images["off"].tobytes(), mode


@pytest.mark.parametrize("mode", REALTIME)
def test_blur_beyond_the_limit_is_clamped(ctx, tmp_path, mode):
    # A bar moving ~20x the blur limit: the filter may only touch pixels within the limit
    # of the bar (the shared blur.max_radius, in pixels, per side).
    sc = scene(tmp_path, WALL + """
        [[objects]]
        mesh = { box = [0.3, 3.0, 0.1] }
        velocity = [400.0, 0.0, 0.0]
    """)
    w, h = 96, 32
    params = ParamSet()
    params.set("blur.max_radius", 0.05)           # 4.8 -> 5 px per side at 96 px
    limit = 5
    images = render_all(ctx, sc, (w, h), modes=["off", mode], params=params)
    r = Renderer(ctx, sc, (w, h))
    try:
        r.render("off", 0.0)
        ids = r.buffers()["id"]
    finally:
        r.release()
    cols = np.nonzero((ids == 2).any(axis=0))[0]
    changed = np.nonzero(np.abs(images[mode] - images["off"]).max(axis=(0, 2)) > 1e-6)[0]
    # ... and does blur it out to the limit (within a pixel): 10-12 columns change.
    assert set(range(cols.min() - limit + 1, cols.max() + limit)) <= set(changed.tolist())
    assert changed.min() >= cols.min() - limit - 1 and changed.max() <= cols.max() + limit + 1


@pytest.mark.parametrize("speed", ["1e21", "1e40"])
def test_absurd_speeds_blur_as_a_fast_one_does(ctx, tmp_path, speed):
    # A bar far past the blur limit at 400 m/s, and at speeds whose displacement's square
    # overflows float32 (1e21 m/s: ~1e20 px) or whose matrices do (1e40 m/s): every filter
    # still blurs it to the limit, as at 400 (length(D) once read inf and the limit's
    # scaling made D zero: no blur). A scene file may not say such speeds (limits.py), but
    # the renderer takes whatever a Scene holds (a parent's speed times a child's).
    images = {}
    for v in ("400.0", speed):
        sc = scene(tmp_path, WALL + """
            [[objects]]
            mesh = { box = [0.3, 3.0, 0.1] }
            velocity = [400.0, 0.0, 0.0]
        """)
        sc.objects[-1].velocity = np.array([float(v), 0.0, 0.0])
        images[v] = render_all(ctx, sc, (96, 32), modes=["off"] + REALTIME)
    for mode in REALTIME:
        fast, absurd, off = images["400.0"][mode], images[speed][mode], images[speed]["off"]
        assert np.isfinite(absurd).all(), mode
        blurred = np.abs(fast - off).max(axis=-1) > 1e-3
        assert blurred.sum() > 100, mode
        # The same blur but for a few pixels (the hybrid's ray mask probes past the screen).
        same = np.abs(absurd - fast).max(axis=-1) < 1e-6
        assert same.mean() > 0.97, (mode, same.mean())


def test_sizes_beyond_the_gl_limit_are_a_clear_error(ctx, tmp_path):
    sc = scene(tmp_path, "")
    with pytest.raises(UserError, match="GL limit"):
        Renderer(ctx, sc, (10 ** 6, 4))
