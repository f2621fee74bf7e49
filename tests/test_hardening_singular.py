"""Singular poses (a keyed scale through zero: a card flipping over) render as their limit
in every mode: no LinAlgError, finite pixels, the image at the singular instant that of an
instant later; invertible poses keep their exact matrices (byte-identical images)."""
from __future__ import annotations

import textwrap

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from viewer.render.graph.params import ParamSet
from viewer.render.modes import MODES
from viewer.render.renderer import Renderer
from world import transforms as tf

from conftest import scene_from

finite = st.floats(min_value=-10.0, max_value=10.0, allow_nan=False)


@settings(derandomize=True, max_examples=300, deadline=None)
@given(st.lists(finite, min_size=9, max_size=9))
def test_the_normal_matrix_is_the_inverse_transpose_where_one_exists(values):
    m4 = np.eye(4)
    m4[:3, :3] = np.reshape(values, (3, 3))
    n = tf.normal_matrix(m4)
    assert n.shape == (3, 3) and np.all(np.isfinite(n))
    try:
        inv_t = np.linalg.inv(m4[:3, :3]).T
    except np.linalg.LinAlgError:
        return
    if np.abs(inv_t).max() <= tf.NORMAL_MATRIX_MAX:
        np.testing.assert_array_equal(n, inv_t)          # exactly: images unchanged
    # the cofactor form points every normal the same way, sign included
    c = tf.cofactor_direction(m4[:3, :3])
    if np.abs(inv_t).max() < 1e6:
        np.testing.assert_allclose(c, inv_t / np.abs(inv_t).max(), atol=1e-9)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.lists(st.sampled_from([0.0, 1e-320, -1e-300, 0.5, -2.0, 3.0]), min_size=3,
                max_size=3),
       st.lists(finite, min_size=3, max_size=3), st.lists(finite, min_size=3, max_size=3))
def test_singular_poses_have_finite_limits(scale, euler, position):
    m4 = tf.translate(position) @ tf.homogeneous(tf.euler_xyz_degrees(euler)) @ tf.scale(scale)
    n = tf.normal_matrix(m4)
    inv = tf.limit_inverse(m4)
    assert np.all(np.isfinite(n)) and np.abs(n).max() <= 1.0 + 1e-12 or \
        np.array_equal(n, np.linalg.inv(m4[:3, :3]).T)
    assert np.all(np.isfinite(inv)) and np.all(np.isfinite(inv.astype(np.float32)))
    # M L M = M: L inverts M on its range (a pseudo-inverse, up to the sheet's thickness)
    np.testing.assert_allclose(m4 @ inv @ m4, m4, atol=1e-5 * (1 + np.abs(m4).max()))
    flat = [abs(s) < 1e-200 for s in scale]
    if sum(flat) == 1:
        # a flattened object: every normal becomes its plane's (the axis scaled to zero)
        axis = tf.euler_xyz_degrees(euler)[:, flat.index(True)]
        for v in np.eye(3):
            w = n @ v
            assert np.linalg.norm(np.cross(w, axis)) < 1e-9 * max(1.0, np.linalg.norm(w))


def test_an_invertible_pose_keeps_numpys_inverse():
    m4 = tf.translate([1.0, 2.0, 3.0]) @ tf.scale([1e-10, 2.0, 3.0])
    np.testing.assert_array_equal(tf.limit_inverse(m4), np.linalg.inv(m4))


FLIP = """
    background = [0.2, 0.3, 0.4]
    ambient = [0.3, 0.3, 0.3]
    [camera]
    position = [{eye}]
    look_at = [0.0, 0.0, 0.0]
    fov_y = 45.0
    shutter = 0.04
    [[lights]]
    direction = [-1.0, -0.5, -0.2]
    [[objects]]
    name = "backdrop"
    mesh = {{ box = [0.1, 20.0, 20.0] }}
    position = [-3.0, 0.0, 0.0]
    material = {{ albedo = [0.9, 0.9, 0.9], texture = {{ kind = "checker", size = 0.5, albedo2 = [0.1, 0.1, 0.1] }} }}
    [[objects]]
    name = "card"
    mesh = {{ box = [1.0, 1.5, 1.5] }}
    material = {{ albedo = [0.8, 0.2, 0.1], specular = 0.4 }}
    [[objects.keys]]
    time = 0.0
    scale = [1.0, 1.0, 1.0]
    [[objects.keys]]
    time = 1.0
    scale = [-1.0, 1.0, 1.0]
    [[objects]]
    name = "ball"
    mesh = {{ sphere = {{ radius = 0.4, subdivisions = 2 }} }}
    [[objects.keys]]
    time = 0.0
    position = [0.5, -0.2, 1.2]
    scale = 1.0
    [[objects.keys]]
    time = 1.0
    position = [0.5, 0.2, 1.2]
    scale = -1.0
"""


@pytest.mark.parametrize("eye", ["4.0, 0.3, 0.2", "0.3, 0.2, 4.0"])
def test_every_mode_renders_a_scale_through_zero_as_its_limit(ctx, tmp_path, eye):
    # At t = 0.5 the card's x scale and the ball's every scale are 0: seen face-on (eye on
    # +x) the card is a flat square, edge-on (eye on +z) nothing; the ball is a point.
    sc = scene_from(tmp_path, FLIP.format(eye=eye))
    params = ParamSet()
    params.set("reference.samples", 8)
    r = Renderer(ctx, sc, (80, 48))
    try:
        for mode in sorted(MODES):
            at = r.render(mode, 0.5, params).image.copy()
            after = r.render(mode, 0.5 + 1e-7, params).image.copy()
            assert np.all(np.isfinite(at)), mode
            diff = np.abs(at - after).max(axis=-1)
            assert (diff < 2e-3).mean() > 0.995 and diff.mean() < 1e-3, (mode, diff.max())
    finally:
        r.release()


CROSSING_CAMERA = """
    [camera]
    fov_y = 45.0
    shutter = 0.04
    [[camera.keys]]
    time = 0.0
    position = [0.0, 0.0, 0.0]
    look_at = [0.0, 0.0, -1.0]
    [[camera.keys]]
    time = 1.0
    position = [0.0, 0.0, -2.0]
    look_at = [0.0, 0.0, -1.0]
    [render]
    width = 32
    height = 18
    time = {t}
    [[objects]]
    mesh = {{ box = [1.0, 1.0, 1.0] }}
    position = [0.0, 0.0, -5.0]
"""


def test_a_keyed_camera_whose_look_at_meets_its_eye_is_one_line(tmp_path, capsys):
    # The eye passes through look_at at t = 0.5: no view exists there (it flips), so no
    # limit either: one line naming the keys and the time; other times render.
    from viewer.commands.main import main
    p = tmp_path / "cam.toml"
    p.write_text(textwrap.dedent(CROSSING_CAMERA.format(t=0.5)))
    assert main(["shot", str(p), "--mode", "off", "--out", str(tmp_path / "a.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hmblur: error: camera.keys: at t = 0.5 s")
    assert sorted(x.name for x in tmp_path.iterdir()) == ["cam.toml"]
    assert main(["shot", str(p), "--mode", "off", "--time", "0.2", "--out",
                 str(tmp_path / "a.png")]) == 0
