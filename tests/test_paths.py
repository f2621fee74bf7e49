"""Curved motion in the hybrid (hybrid.segments, glsl/passes/path.glsl): the G-buffer's path points
against a numpy projection of M(t_k) for a rotating object, a straight path that changes
nothing the mask sees, and a reversal (an object that goes and comes back within the
exposure: chord 0) masked and blurred, the ray mask on synthetic paths against a numpy
statement of glsl/modes/hybrid/raymask_displacement.frag's path probes.

Synthetic arrays are in GL orientation (row 0 at the bottom, offsets y up) as in
tests/test_raymask.py; `to_image` flips to and from the frames' image orientation.
"""
from __future__ import annotations

import numpy as np
import pytest

import numpy_hybrid as nh
from conftest import CONFORMANCE
from test_hybrid import composite_stage
from world.camera import Camera
from world.conventions import to_image
from viewer.render.graph.params import ParamSet
from viewer.render.passes.gbuffer import GBUFFER, path_targets, path_times
from viewer.render.modes.hybrid.config import HybridConfig
from viewer.render.modes.hybrid.mask import raymask_passes
from viewer.render.renderer import Renderer
from viewer.render.modes.hybrid.reveal import BACK, PACKED
from world.loader import load_scene
from raytrace import RayScene
from raytrace.reveal import reveal

SIZE = (64, 36)
W, H = 40, 6
BAR = (12, 24)


def render(ctx, scene, segments, size=SIZE, mode="hybrid"):
    p = ParamSet()
    p.set("hybrid.segments", segments)
    r = Renderer(ctx, scene, size)
    try:
        res = r.render(mode, scene.render.time, p, seed=0)
        return res, r.buffers()
    finally:
        r.release()


def stored_path(bufs, segments) -> np.ndarray:
    """(H, W, K + 1, 2) path offsets (image rows, GL axes) from the path targets."""
    slots = np.concatenate([bufs[n].reshape(*bufs[n].shape[:2], 2, 2)
                            for n in path_targets(segments)], axis=2)
    mid = np.zeros(slots.shape[:2] + (1, 2), slots.dtype)
    return np.concatenate([slots[:, :, :segments // 2], mid, slots[:, :, segments // 2:]], 2)


def window(cam, t, world, size):
    """Window positions (GL px, y up) of world points seen by `cam` at time t."""
    clip = (cam.projection() @ cam.view(t) @ np.c_[world, np.ones(len(world))].T).T
    ndc = clip[:, :2] / clip[:, 3:4]
    return (ndc * 0.5 + 0.5) * np.asarray(size, float)


@pytest.mark.parametrize("segments", [2, 4])
def test_path_points_are_the_projections_of_m_at_t_k(ctx, segments):
    # basic.toml's box spins about Y (15 rad/s over a 0.05 s shutter): its points' screen
    # paths bend. Each pixel's path point k is where its surface point (found by a
    # primary ray, taken to mesh space by M(t)^-1) is seen at t_k, minus where it is now.
    scene = load_scene(CONFORMANCE / "basic.toml")
    box = next(o for o in scene.objects if o.name == "box")
    _, bufs = render(ctx, scene, segments)
    ids = bufs["hybrid_front"][..., 3]
    jj, ii = np.nonzero(ids == box.id)
    cam = Camera(scene.camera, *SIZE)
    t = scene.render.time
    layer = reveal(RayScene(scene), cam, t, np.c_[ii, jj], np.zeros(len(ii)), threads=1).layer
    hit = layer.object_id == box.id               # (silhouette pixels may disagree)
    assert hit.sum() > 40
    world = layer.world_position[hit]
    local = (np.linalg.inv(box.matrix(t)) @ np.c_[world, np.ones(len(world))].T).T[:, :3]
    now = window(cam, t, world, SIZE)
    got = stored_path(bufs, segments)[jj[hit], ii[hit]]
    t_open, t_close = scene.exposure(t)
    for k, tk in enumerate(path_times(t_open, t_close, segments)):
        at_k = (box.matrix(tk) @ np.c_[local, np.ones(len(local))].T).T[:, :3]
        np.testing.assert_allclose(got[:, k], window(cam, tk, at_k, SIZE) - now, atol=0.02)
    # The chord is the G-buffer's displacement D; the path bends (not D's straight line).
    d = bufs["hybrid_front"][jj[hit], ii[hit], :2]
    np.testing.assert_allclose(got[:, -1] - got[:, 0], d, atol=1e-4)
    bend = got[:, segments // 2] - 0.5 * (got[:, 0] + got[:, -1])
    assert np.abs(bend).max() > 0.2           # (px; the points agree to 0.02)


def test_one_segment_writes_no_path_and_a_straight_path_masks_the_same(ctx):
    # The sphere of basic.toml translates across the view at constant depth: its screen
    # path is a straight line at constant speed, so its path points are -D/2, 0, D/2 and
    # the ray mask is the chord's.
    scene = load_scene(CONFORMANCE / "basic.toml")
    sphere = next(o for o in scene.objects if o.name == "sphere")
    one_res, one = render(ctx, scene, 1)
    two_res, two = render(ctx, scene, 2)
    assert "hybrid_path" not in one and "hybrid_path" in two
    np.testing.assert_array_equal(one["hybrid_front"], two["hybrid_front"])
    on = two["hybrid_front"][..., 3] == sphere.id
    path = stored_path(two, 2)[on]
    d = two["hybrid_front"][on][:, :2]
    np.testing.assert_allclose(path[:, 0], -0.5 * d, atol=2e-3)
    np.testing.assert_allclose(path[:, 2], 0.5 * d, atol=2e-3)
    masked = one["ray_mask"] == sphere.id
    assert masked.sum() > 20
    np.testing.assert_array_equal(two["ray_mask"] == sphere.id, masked)


# ---- the ray mask and the composite on synthetic paths ------------------------------------------

def params(segments, **hy):
    p = ParamSet()
    p.set("blur.max_radius", 0.25)          # k = 10 px at W = 40
    p.set("hybrid.segments", segments)
    for key, value in hy.items():
        p.set(f"hybrid.{key}", value)
    return p


def upload(frame, name, a, spec=None):
    frame.pool.texture(name, spec or GBUFFER.get(name) or PACKED)
    frame.write(name, to_image(np.asarray(a, np.float32)))


def upload_front(frame, depth, ids, paths):
    """hybrid_front (chord, depth, id) and the path targets of (H, W, K + 1, 2) paths."""
    segments = paths.shape[2] - 1
    chord = paths[:, :, -1] - paths[:, :, 0]
    upload(frame, "hybrid_front", np.dstack([chord, depth, ids]))
    slots = np.delete(paths, segments // 2, axis=2)
    for j, name in enumerate(path_targets(segments)):
        upload(frame, name, slots[:, :, 2 * j:2 * j + 2].reshape(H, W, 4))


def bar(paths_bar, paths_bg=None):
    """A bar (id 2, depth 2) over a wall (id 1, depth 10) with the given path offsets."""
    k1 = len(paths_bar)
    depth = np.full((H, W), 10.0)
    ids = np.ones((H, W))
    paths = np.zeros((H, W, k1, 2))
    if paths_bg is not None:
        paths[:] = paths_bg
    depth[:, BAR[0]:BAR[1]] = 2.0
    ids[:, BAR[0]:BAR[1]] = 2
    paths[:, BAR[0]:BAR[1]] = paths_bar
    return depth, ids, paths


def run_mask(frame):
    for p in raymask_passes(HybridConfig.of(frame.params)):
        p.allocate(frame)
        p.execute(frame)
    return to_image(frame.read("ray_mask"))


def numpy_path_mask(depth, ids, paths, min_speed=1.0, threshold=0.01):
    """glsl/modes/hybrid/raymask_displacement.frag STEP 3 with a path: pixel X of object I is masked when
    X - (o_k - o_bg,k) shows another, farther object for some point k, o_bg the path of
    the first background seen at a probe X - o_k (none seen: not masked)."""
    h, w = ids.shape
    f32 = np.float32
    paths = paths.astype(f32)
    mid = (paths.shape[2] - 1) // 2
    out = np.zeros((h, w), np.uint32)
    for y in range(h):
        for x in range(w):
            o = paths[y, x]
            extent = 2.0 * np.sqrt(max(float(f32(v @ v)) for v in o))
            if ids[y, x] == 0 or extent < min_speed:
                continue

            def far(offset):
                px, py = nh.probe(x, y, offset, (w, h))
                return (ids[py, px] != ids[y, x]
                        and f32(depth[py, px]) > f32(depth[y, x]) * f32(1.0 + threshold)), (px, py)

            seen = [far(-o[k])[1] for k in range(len(o)) if k != mid and far(-o[k])[0]]
            if not seen:
                continue
            b = paths[seen[0][1], seen[0][0]]
            if any(far(b[k] - o[k])[0] for k in range(len(o)) if k != mid):
                out[y, x] = ids[y, x]
    return out


def reversal(segments, reach=5.3):
    """A bar that goes right by `reach` px and comes back within the exposure (chord 0):
    K = 2: at +reach at both ends, at the frame time in between; K = 4: at +reach at the
    quarter times, at 0 at the ends and the frame time."""
    x = {2: [reach, 0.0, reach], 4: [0.0, reach, 0.0, reach, 0.0]}[segments]
    return np.c_[x, np.zeros(segments + 1)]


@pytest.mark.parametrize("segments", [2, 4])
def test_a_reversal_with_a_zero_chord_is_still_masked(synthetic_frame, segments):
    # Either way the bar leaves 5.3 px of the wall at its left edge bare at some time,
    # and the chord is 0.
    path = reversal(segments)
    assert np.allclose(path[-1] - path[0], 0.0)
    depth, ids, paths = bar(path)
    frame = synthetic_frame((W, H), params(segments))
    upload_front(frame, depth, ids, paths)
    got = run_mask(frame)
    want = numpy_path_mask(depth, ids, paths)
    np.testing.assert_array_equal(got, want)
    assert [int(x) for x in np.flatnonzero(got[2])] == list(range(12, 17))
    # The chord alone sees no motion at all.
    frame = synthetic_frame((W, H), params(1))
    upload(frame, "hybrid_front", np.dstack([np.zeros((H, W, 2)), depth, ids]))
    assert not run_mask(frame).any()


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("segments", [2, 4])
def test_path_mask_matches_numpy_on_random_paths(synthetic_frame, seed, segments):
    rng = np.random.default_rng(seed)
    bar_path = rng.uniform(-6.0, 6.0, (segments + 1, 2)) * [1.0, 0.3]
    bg_path = rng.uniform(-2.0, 2.0, (segments + 1, 2)) * [1.0, 0.3]
    for p in (bar_path, bg_path):
        p[segments // 2] = 0.0
    depth, ids, paths = bar(bar_path, bg_path)
    paths += rng.uniform(-0.7, 0.7, paths.shape) * (np.arange(segments + 1) != segments // 2)[:, None]
    frame = synthetic_frame((W, H), params(segments))
    upload_front(frame, depth, ids, paths)
    got = run_mask(frame)
    np.testing.assert_array_equal(got, numpy_path_mask(depth, ids, paths))
    assert got.any()


def test_a_reversal_is_blurred_by_the_composite(synthetic_frame):
    # The bar coming back: over the exposure it covers [12, 24) + [0, 5.3] px, so the wall
    # just right of it is covered part of the time and the bar's left pixels are bare part
    # of the time: both blend. With one segment (chord 0) the composite keeps them sharp.
    rng = np.random.default_rng(3)
    depth, ids, paths = bar(reversal(2))
    colour = np.where((ids == 2)[..., None], [0.9, 0.2, 0.1], [0.1, 0.3, 0.8])
    colour = colour + rng.uniform(0, 0.05, colour.shape)
    images = {}
    for segments in (1, 2):
        frame = synthetic_frame((W, H), params(segments, jitter=0.0))
        upload(frame, "color", np.dstack([colour, np.ones((H, W))]))
        if segments == 1:
            upload(frame, "hybrid_front", np.dstack([np.zeros((H, W, 2)), depth, ids]))
        else:
            upload_front(frame, depth, ids, paths)
        for name in BACK:
            upload(frame, name, np.zeros((H, W, 4)))
        for p in composite_stage(HybridConfig.of(frame.params)):
            p.allocate(frame)
            p.execute(frame)
        images[segments] = to_image(frame.read("hybrid"))[..., :3]
    np.testing.assert_allclose(images[1], colour, atol=1e-6)
    row = images[2][2]
    # Wall pixels within the bar's reach turn red in part; beyond it they stay blue.
    assert all(row[x, 0] > colour[2, x, 0] + 0.15 for x in (24, 25, 26, 27))
    np.testing.assert_allclose(row[31:], colour[2, 31:], atol=1e-6)
    # The bar's pixels near its left edge are bare for part of the exposure.
    assert all(row[x, 0] < colour[2, x, 0] - 0.15 for x in (12, 13))


def test_path_buffers_are_shown_as_motion():
    # The viewer's buffer view and the --buffers pictures draw a path target's first point
    # as a velocity (colour wheel), not as a colour.
    from viewer.render.passes.debug_view import auto_kind
    from viewer.io.visualize import colour_wheel, visualise
    for name in path_targets(4):
        assert auto_kind(name, GBUFFER[name]) == ("velocity", 0)
    a = np.random.default_rng(0).normal(size=(3, 5, 4)).astype(np.float32)
    np.testing.assert_array_equal(visualise("hybrid_path", a), colour_wheel(a[..., :2].astype(np.float64)))
