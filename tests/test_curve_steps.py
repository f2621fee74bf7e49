"""Curve steps: how far screen paths stray from their chords (world/path_bend.py), against
the geometry worked out by hand, and the sub-exposure steps a mode takes for it
(viewer/render/steps.py): the hybrid's default follows bending motion with 2 sub-frames,
straight motion and the published filters stay one linear blur."""
import math

import numpy as np
import pytest

from viewer.render.graph.params import ParamSet
from viewer.render.renderer import Renderer
from viewer.render.steps import curve_steps, step_count
from world.camera import Camera
from world.path_bend import FRACTIONS, screen_bend

from conftest import scene_from

W, H, FOV = 200, 100, 40.0
SHUTTER = 0.1
# The camera on +z looking down -z: a point (x, y, 0) lands at the image centre plus
# F (x, y) / DIST px.
DIST = 5.0
F = (H / 2) / math.tan(math.radians(FOV / 2))


def scene_text(obj: str) -> str:
    return f"""
        [camera]
        position = [0.0, 0.0, {DIST}]
        look_at = [0.0, 0.0, 0.0]
        fov_y = {FOV}
        shutter = {SHUTTER}
        [[lights]]
        direction = [0.0, 0.0, -1.0]
        color = [1.0, 1.0, 1.0]
        [[objects]]
        name = "backdrop"
        mesh = {{ box = [8.0, 8.0, 0.1] }}
        position = [0.0, 0.0, -1.0]
        material = {{ albedo = [0.8, 0.8, 0.8], texture = {{ kind = "checker", size = 0.25, albedo2 = [0.1, 0.1, 0.1] }} }}
        {obj}
    """


def bend_of(tmp_path, obj: str, t: float = 0.0) -> float:
    sc = scene_from(tmp_path, scene_text(obj))
    return screen_bend(sc, Camera(sc.camera, W, H), t, SHUTTER)


def test_uniform_motion_across_the_view_does_not_bend(tmp_path):
    # (a translation parallel to the image plane projects to uniform screen motion)
    obj = """[[objects]]
        mesh = { box = [0.4, 0.4, 0.4] }
        velocity = [3.0, 1.0, 0.0]"""
    assert bend_of(tmp_path, obj) < 1e-9


def test_a_spin_about_the_view_axis_bends_by_its_sagitta(tmp_path):
    w = 6.0                                     # rad/s about z: 0.6 rad over the shutter
    obj = f"""[[objects]]
        mesh = {{ box = [1.0, 1.0, 0.0001] }}
        angular_velocity = [0.0, 0.0, {w}]"""
    # The corners (x, y) = (+-0.5, +-0.5) turn on a circle of r = F sqrt(0.5) / (DIST -
    # ~0) px through angles w (t - 0); the largest departure from the chord over the
    # sampled fractions (the middle one: the sagitta r (1 - cos(theta / 2))).
    r = F * math.sqrt(0.5) / (DIST - 0.00005)
    angles = w * SHUTTER * (FRACTIONS - 0.5)
    path = r * np.c_[np.cos(angles), np.sin(angles)]
    chord = path[0] + FRACTIONS[:, None] * (path[-1] - path[0])
    expected = np.sqrt(((path - chord) ** 2).sum(1)).max()
    assert expected == pytest.approx(r * (1 - math.cos(w * SHUTTER / 2)), rel=1e-12)
    assert bend_of(tmp_path, obj) == pytest.approx(expected, rel=1e-6)


def test_a_bounce_bends_by_how_far_it_goes_out(tmp_path):
    # Linear keys down and back up inside the shutter: the chord is zero, the path goes
    # 0.3 world units (F 0.3 / DIST px) out and back.
    h = SHUTTER / 2
    obj = f"""[[objects]]
        mesh = {{ box = [0.2, 0.2, 0.0001] }}
        [[objects.keys]]
        time = {-h}
        position = [0.0, 0.3, 0.0]
        [[objects.keys]]
        time = 0.0
        position = [0.0, 0.0, 0.0]
        [[objects.keys]]
        time = {h}
        position = [0.0, 0.3, 0.0]"""
    assert bend_of(tmp_path, obj) == pytest.approx(F * 0.3 / (DIST - 0.00005), rel=1e-6)


def test_approach_bends_by_its_change_of_speed(tmp_path):
    # Straight at the camera, off-centre: the screen path is straight but not uniform.
    vz, x0 = 20.0, 1.0
    obj = f"""[[objects]]
        mesh = {{ box = [0.0001, 0.0001, 0.0001] }}
        position = [{x0}, 0.0, 0.0]
        velocity = [0.0, 0.0, {vz}]"""
    z = vz * SHUTTER * (FRACTIONS - 0.5)
    x = F * x0 / (DIST - z)
    expected = np.abs(x - (x[0] + FRACTIONS * (x[-1] - x[0]))).max()
    assert expected > 1.0
    assert bend_of(tmp_path, obj) == pytest.approx(expected, rel=1e-3)   # (the box's size)


def test_nothing_moving_or_a_closed_shutter_is_straight(tmp_path):
    sc = scene_from(tmp_path, scene_text(""))
    cam = Camera(sc.camera, W, H)
    assert screen_bend(sc, cam, 0.0, SHUTTER) == 0.0
    spin = scene_from(tmp_path, scene_text("""[[objects]]
        mesh = { box = [1.0, 1.0, 1.0] }
        angular_velocity = [0.0, 0.0, 6.0]"""), "spin")
    assert screen_bend(spin, Camera(spin.camera, W, H), 0.0, 0.0) == 0.0


def test_points_behind_the_camera_are_left_out(tmp_path):
    # A spinning box behind the eye: its projection is no position, and it is not seen.
    obj = f"""[[objects]]
        mesh = {{ box = [1.0, 1.0, 1.0] }}
        position = [0.0, 0.0, {DIST + 3.0}]
        angular_velocity = [0.0, 0.0, 6.0]"""
    assert bend_of(tmp_path, obj) == 0.0


@pytest.mark.parametrize("bend, most, n", [(0.5, 2, 1), (1.0, 2, 1), (1.01, 2, 2),
                                           (20.0, 2, 2), (20.0, 16, 5), (4.0, 16, 2),
                                           (4.01, 16, 3), (1000.0, 16, 16), (50.0, 1, 1)])
def test_curve_step_count(bend, most, n):
    assert curve_steps(bend, 1.0, most) == n


def test_step_count_per_mode():
    p = ParamSet()
    bend = lambda: 3.0                      # noqa: E731
    assert step_count("hybrid", p, 0.05, bend) == 2
    assert step_count("mcguire", p, 0.05, bend) == 1          # the published blur
    assert step_count("hybrid", p, 0.05, lambda: 0.9) == 1
    assert step_count("hybrid", p, 0.0, bend) == 1             # no exposure
    p.set("motion.steps", 4)
    assert step_count("hybrid", p, 0.05, bend) == 4            # the larger count
    p.set("motion.steps", 1)
    p.set("hybrid.curve_steps", 1)
    asked = []
    assert step_count("hybrid", p, 0.05, lambda: asked.append(1) or 3.0) == 1
    assert not asked                                           # not measured when moot
    p.set("mcguire.curve_steps", 4)
    p.set("motion.curve_px", 0.5)
    assert step_count("mcguire", p, 0.05, bend) == 3           # ceil(sqrt(3 / 0.5))


SPIN = """[[objects]]
        mesh = { box = [1.6, 0.5, 0.3] }
        angular_velocity = [0.0, 0.0, 15.0]
        material = { albedo = [0.9, 0.2, 0.1] }"""
SLIDE = """[[objects]]
        mesh = { box = [0.8, 0.8, 0.3] }
        velocity = [8.0, 0.0, 0.0]
        material = { albedo = [0.9, 0.2, 0.1] }"""


@pytest.fixture
def renderers(ctx, tmp_path):
    made = []

    def make(obj):
        r = Renderer(ctx, scene_from(tmp_path, scene_text(obj), f"s{len(made)}"), (W, H))
        made.append(r)
        return r
    yield make
    for r in made:
        r.release()


def params(**sets) -> ParamSet:
    p = ParamSet()
    for k, v in sets.items():
        p.set(k.replace("__", "."), v)
    return p


def test_the_default_hybrid_takes_two_steps_on_a_spin(renderers):
    r = renderers(SPIN)
    assert screen_bend(r.scene, r.camera, 0.0, SHUTTER) > 4.0
    res = r.render("hybrid", 0.0, ParamSet())
    two = r.render("hybrid", 0.0, params(motion__steps=2, hybrid__curve_steps=1))
    one = r.render("hybrid", 0.0, params(hybrid__curve_steps=1))
    assert np.array_equal(res.image, two.image)
    assert not np.array_equal(res.image, one.image)
    assert res.stats["steps"] == 2 and res.stats["bend_px"] > 4.0
    assert "motion_bend" in res.pass_ms
    # McGuire keeps the published linear blur unless asked.
    mc = r.render("mcguire", 0.0, ParamSet())
    assert np.array_equal(mc.image, r.render("mcguire", 0.0, params(mcguire__curve_steps=1)).image)
    assert "steps" not in mc.stats and "motion_bend" not in mc.pass_ms


def test_straight_uniform_motion_stays_one_linear_blur(renderers):
    r = renderers(SLIDE)
    res = r.render("hybrid", 0.0, ParamSet())
    assert res.stats["bend_px"] < 1e-6 and "steps" not in res.stats
    assert np.array_equal(res.image, r.render("hybrid", 0.0, params(hybrid__curve_steps=1)).image)


def test_two_curve_steps_are_closer_to_the_reference_on_a_spin(renderers):
    r = renderers(SPIN)
    ref = r.render("reference", 0.0, params(reference__samples=64)).image
    err = {k: float(np.abs(r.render("hybrid", 0.0, params(hybrid__curve_steps=k)).image
                           - ref).mean()) for k in (1, 2)}
    assert err[2] < 0.8 * err[1], err
