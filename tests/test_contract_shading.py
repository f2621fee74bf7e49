"""The image contract's shading and the reference's averaging, against numpy written from
the contract's formulas (independent of the code under test): normals through the inverse
transpose of M's upper 3x3 under a non-uniform scale; the reference averaging unclamped
sub-frames at the stratified times t - s/2 + (k + 0.5) s / N and clamping once."""

import numpy as np

from viewer.io.imageio import linear_to_srgb8
from viewer.render.graph.params import ParamSet
from viewer.render.renderer import Renderer

from conftest import scene_from

W, H = 96, 64


ELLIPSOID = """
    ambient = [0.05, 0.05, 0.05]
    [camera]
    position = [0.0, 0.0, 5.0]
    look_at = [0.0, 0.0, 0.0]
    fov_y = 40.0
    [[lights]]
    direction = [-0.5, -0.6, -0.6]
    color = [0.9, 0.9, 0.9]
    [[objects]]
    mesh = { sphere = { radius = 1.0, subdivisions = 4 } }
    position = [0.2, 0.0, 0.0]
    scale = [1.8, 0.6, 1.0]
    shading = "smooth"
    material = { albedo = [0.8, 0.7, 0.6] }
"""


def test_normals_use_the_inverse_transpose_under_a_non_uniform_scale(ctx, tmp_path):
    scene = scene_from(tmp_path, ELLIPSOID)
    r = Renderer(ctx, scene, (W, H))
    try:
        img = r.render("off", 0.0).image
        depth, ids = r.buffers()["depth"], r.buffers()["id"]
    finally:
        r.release()
    # Interior pixels of the ellipsoid (its 4 neighbours too: no silhouette pixels).
    inside = ids == 1
    inside[1:-1, 1:-1] &= inside[:-2, 1:-1] & inside[2:, 1:-1] & inside[1:-1, :-2] & inside[1:-1, 2:]
    inside[[0, -1], :] = inside[:, [0, -1]] = False
    jj, ii = np.nonzero(inside)
    assert len(ii) > 900
    # The surface point from the camera ray and the linear view depth.
    o, d = r.camera.rays(0.0, ii, jj)
    fwd = np.array([0.0, 0.0, -1.0])
    p = o + d * (depth[jj, ii] / (d @ fwd))[:, None]
    # M = T(0.2, 0, 0) S(1.8, 0.6, 1): the mesh point and its (sphere's radial) normal.
    s = np.array([1.8, 0.6, 1.0])
    local = (p - [0.2, 0.0, 0.0]) / s
    n_local = local / np.linalg.norm(local, axis=1, keepdims=True)
    n = n_local @ np.linalg.inv(np.diag(s)).T.T        # (inverse transpose of S) n_local
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    v = o - p
    n[np.einsum("ij,ij->i", n, v) < 0] *= -1
    light = -np.array([-0.5, -0.6, -0.6]) / np.linalg.norm([-0.5, -0.6, -0.6])
    want = np.array([0.8, 0.7, 0.6]) * (0.05 + 0.9 * np.maximum(0.0, n @ light)[:, None])
    err = np.abs(img[jj, ii] - want)
    # The mesh's interpolated normals are the sphere's to within its facets (measured
    # 0.0002 mean, 0.0022 max); the plain model matrix's normals miss by 0.13 mean.
    assert err.mean() < 0.001 and err.max() < 0.01, (err.mean(), err.max())


BRIGHT = """
    [camera]
    position = [0.0, 0.0, 5.0]
    look_at = [0.0, 0.0, 0.0]
    fov_y = 40.0
    shutter = 0.1
    [[lights]]
    direction = [0.0, 0.0, -1.0]
    color = [4.0, 4.0, 4.0]
    [[objects]]
    mesh = { box = [1.0, 1.0, 1.0] }
    velocity = [12.0, 0.0, 0.0]
    material = { albedo = [0.5, 0.5, 0.5] }
"""


def test_reference_averages_unclamped_sub_frames_at_the_stratified_times(ctx, tmp_path):
    """A box lit at 2x the white point sweeps 1.2 units in the exposure: where it covers
    a pixel part of the exposure, the mean of unclamped sub-frames is brighter than the
    mean of clamped ones (1.0 against 0.5 at half coverage), and where the times stand
    decides which pixels it covers."""
    scene = scene_from(tmp_path, BRIGHT)
    n, t, shutter = 5, 0.02, 0.1
    times = t - shutter / 2 + (np.arange(n) + 0.5) * shutter / n     # the contract's
    r = Renderer(ctx, scene, (W, H))
    try:
        p = ParamSet()
        p.set("reference.samples", n)
        ref = r.render("reference", t, p).image
        subs = np.stack([r.render("off", float(tk)).image for tk in times]).astype(np.float64)
    finally:
        r.release()
    assert subs.max() > 1.9                      # over-bright sub-frames
    want = np.clip(subs.mean(axis=0), 0.0, 1.0)
    got, exp = linear_to_srgb8(ref).astype(int), linear_to_srgb8(want).astype(int)
    assert np.abs(got - exp).max() <= 1
    partial = (subs[..., 0] > 0).any(0) & ~(subs[..., 0] > 0).all(0)
    assert partial.sum() > 300                   # the blur, where clamping first would show
    # The test can tell: clamping each sub-frame first would darken hundreds of them.
    first = linear_to_srgb8(np.clip(subs, 0.0, 1.0).mean(axis=0)).astype(int)
    assert (np.abs(first - exp).max(-1) > 20).sum() > 200
