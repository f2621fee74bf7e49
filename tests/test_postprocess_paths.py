"""Path motion in the post-process gathers (mcguire.segments, guertin.segments): the K = 2
McGuire gather on a tiny synthetic buffer against a numpy statement of its extension
(glsl/modes/mcguire_gather.frag: taps split over the segments, per-segment weights), one segment
unchanged, and a rotating scene closer to the reference with two segments than one.

Synthetic arrays are in GL orientation (row 0 at the bottom, offsets y up); `to_image`
flips to and from the frames' image orientation.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import numpy_mcguire as nm
from conftest import CONFORMANCE
from world.conventions import to_image
from viewer.render.graph.params import ParamSet
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.passes.gbuffer import GBUFFER, path_names, path_samplers, path_targets
from viewer.render.passes.half_velocity import path_bindings
from viewer.render.modes.mcguire import EARLY_OUT_PX, JITTER_STREAM, Gather, McGuireConfig
from viewer.render.graph.pool import TexSpec
from viewer.render.renderer import Renderer
from world.loader import load_scene

F32 = np.float32
SIZE = (32, 16)


# ---- numpy statement of glsl/passes/path.glsl and the McGuire path gather ---------------------------

def path_at(o, u, segments):
    """o (..., K+1, 2) at time u (a scalar or (...)) of the exposure, linear per segment."""
    f = np.clip((np.asarray(u, np.float64) + 0.5) * segments, 0.0, segments)
    k = np.minimum(f.astype(int), segments - 1)
    a = np.take_along_axis(o, k[..., None, None], axis=-2)[..., 0, :]
    b = np.take_along_axis(o, (k + 1)[..., None, None], axis=-2)[..., 0, :]
    return a + (b - a) * (f - k)[..., None], k


def extent(o):
    return 2.0 * np.sqrt((o * o).sum(-1).max(-1))


def clamp_path(o, limit):
    e = extent(o)
    return o * np.where(e > limit, limit / np.maximum(e, 1e-30), 1.0)[..., None, None]


def piece(o, s):
    """|o[s+1] - o[s]| per pixel, s (...) the segment."""
    a = np.take_along_axis(o, s[..., None, None], axis=-2)[..., 0, :]
    b = np.take_along_axis(o, (s + 1)[..., None, None], axis=-2)[..., 0, :]
    return np.hypot(*(b - a).transpose(-1, *range(b.ndim - 1)))


def mcguire_path_gather(color, depth, paths, tile_paths, k, segments, samples=15,
                        soft_z=0.1, jitter=1.0, seed=0, kappa=0.0):
    """The gather with paths (H, W, K+1, 2) and the NeighborMax paths (tiles): returns
    (out, ambiguous) as numpy_mcguire.gather."""
    color = np.asarray(color, np.float64)[..., :3]
    h, w = depth.shape
    ys, xs = np.mgrid[0:h, 0:w]
    on_raw = tile_paths[ys // k, xs // k].astype(np.float64)
    still = 0.5 * extent(on_raw) <= EARLY_OUT_PX
    on = clamp_path(on_raw, 2.0 * k)
    op = clamp_path(paths.astype(np.float64), 2.0 * k)
    rx = np.clip(0.5 * extent(op), 0.5, k)
    zx = depth.astype(np.float64)
    wsum = (samples / (kappa * rx)) if kappa > 0 else 1.0 / rx
    acc = wsum[..., None] * color
    j = (F32(jitter) * (nm.hash01(xs, ys, seed, JITTER_STREAM) - 0.5).astype(F32)).astype(F32)
    ambiguous = np.zeros((h, w), bool)
    for t in nm.tap_offsets(samples, j):
        u = -0.5 * t.astype(np.float64)
        at, s = path_at(on, u, segments)
        px = (xs + 0.5 - at[..., 0]).astype(F32)
        py = (ys + 0.5 - at[..., 1]).astype(F32)
        yx, yy = nm.tap_pixel(px, py, w, h, ambiguous, ~still)
        dist = np.abs(u) * segments * piece(on, s)
        ry = np.clip(0.5 * segments * piece(op[yy, yx], s), 0.5, k)
        rxs = np.clip(0.5 * segments * piece(op, s), 0.5, k)
        zy = zx[yy, yx]
        a = (nm.front(zy, zx, soft_z) * nm.cone(dist, ry)
             + nm.front(zx, zy, soft_z) * nm.cone(dist, rxs)
             + 2.0 * nm.cylinder(dist, ry) * nm.cylinder(dist, rxs))
        wsum = wsum + a
        acc = acc + a[..., None] * color[yy, yx]
    return np.where(still[..., None], color, acc / wsum[..., None]), ambiguous


# ---- the GPU gather on synthetic buffers -----------------------------------------------------

def curved_scene(rng, h, w, k):
    """A far plane moving along a bent path, a near slab along another, a still corner;
    NeighborMax paths per tile: the slab's where a tile meets it, else the plane's, one
    tile still (its early out)."""
    color = rng.uniform(0, 1, (h, w, 3))
    depth = np.full((h, w), 8.0)
    paths = np.zeros((h, w, 3, 2))
    paths[:] = [[-1.5, 0.4], [0.0, 0.0], [0.9, 1.1]]
    paths[4:11, 9:20] = [[-3.1, -2.3], [0.0, 0.0], [3.7, -1.9]]
    depth[4:11, 9:20] = 2.0 + 0.01 * rng.uniform(size=(7, 11))
    paths[:, 28:] = 0.0
    th, tw = -(-h // k), -(-w // k)
    tiles = np.zeros((th, tw, 3, 2))
    tiles[:] = paths[0, 0]
    for ty in range(th):
        for tx in range(tw):
            # the 3x3 tiles around (tx, ty) meet the slab (rows 4..10, columns 9..19)
            if ty * k - k < 11 and ty * k + 2 * k > 4 and tx * k - k < 20 and tx * k + 2 * k > 9:
                tiles[ty, tx] = paths[5, 10]
    tiles[0, tw - 1] = 0.0
    return color, depth, paths, tiles


def upload(frame, name, a, spec):
    frame.pool.texture(name, spec)
    frame.write(name, to_image(np.asarray(a, np.float32)))


def pack(paths):
    """(H, W, 3, 2) K = 2 points -> the RGBA target (o0, o2): the middle point is 0."""
    return np.concatenate([paths[..., 0, :], paths[..., 2, :]], axis=-1)


@pytest.mark.parametrize("jitter,seed,samples", [(0.0, 0, 15), (1.0, 5, 9)])
def test_two_segment_gather_matches_numpy(synthetic_frame, jitter, seed, samples):
    rng = np.random.default_rng(11)
    w, h = SIZE
    p = ParamSet()
    p.set("blur.max_radius", 0.25)
    p.set("mcguire.segments", 2)
    p.set("mcguire.jitter", jitter)
    p.set("mcguire.samples", samples)
    frame = synthetic_frame(SIZE, p, seed=seed)
    k = max_radius_px(frame)
    color, depth, paths, tiles = curved_scene(rng, h, w, k)
    rgba = np.concatenate([color, np.ones((h, w, 1))], axis=2)
    upload(frame, "color", rgba, GBUFFER["color"])
    upload(frame, "depth", depth, GBUFFER["depth"])
    upload(frame, "hybrid_path", pack(paths), GBUFFER["hybrid_path"])
    upload(frame, "mcguire_velocity", np.zeros((h, w, 2)), TexSpec(2, "f4"))
    upload(frame, "mcguire_neighbormax", np.zeros(tiles.shape[:2] + (2,)),
           TexSpec(2, "f4", tile=k))
    upload(frame, "mcguire_neighbormax_path", pack(tiles), TexSpec(4, "f4", tile=k))
    g = Gather(tiled=True, config=McGuireConfig(2))
    g.allocate(frame)
    g.execute(frame)
    assert frame.stats["mcguire_neighbormax_gather_tiles"] == tiles.shape[0] * tiles.shape[1] - 1
    out = to_image(frame.read("mcguire"))[..., :3].astype(np.float64)
    ref, amb = mcguire_path_gather(color, depth, paths, tiles, k, 2, samples=samples,
                                   jitter=jitter, seed=seed)
    assert amb.mean() < 0.2
    np.testing.assert_allclose(out[~amb], ref[~amb], rtol=1e-4, atol=1e-5)
    still = slice(0, k), slice(w - k, w)              # the still tile keeps its colour
    np.testing.assert_array_equal(out[still], color[still].astype(np.float32))
    assert np.abs(out - color).max() > 0.05              # and the rest is blurred


# ---- whole frames ----------------------------------------------------------------------------

def render(ctx, scene, mode, settings, size=(64, 36), seed=0):
    p = ParamSet()
    for key, value in settings.items():
        p.set(key, value)
    r = Renderer(ctx, scene, size)
    try:
        return r.render(mode, scene.render.time, p, seed=seed).image[..., :3].astype(np.float64)
    finally:
        r.release()


def test_path_target_names_and_their_samplers():
    # Two path points a target: one segment (the chord) has none, 2 one, 4 two.
    assert [path_names("t", k) for k in (1, 2, 4)] == [(), ("t_path",), ("t_path", "t_path2")]
    assert path_targets(4) == ("hybrid_path", "hybrid_path2")
    assert path_samplers(("a", "b")) == {"u_path0": "a", "u_path1": "b"}
    assert path_bindings("nm", 1) == {}
    assert list(path_bindings("nm", 4).items()) == [
        ("u_path0", "hybrid_path"), ("u_tile_path0", "nm_path"),
        ("u_path1", "hybrid_path2"), ("u_tile_path1", "nm_path2")]


@pytest.mark.parametrize("mode", ["mcguire", "guertin", "ue4"])
def test_one_segment_is_the_default_and_writes_no_path(ctx, mode):
    scene = load_scene(CONFORMANCE / "keys_arc.toml")
    assert ParamSet()[mode].segments == 1
    np.testing.assert_array_equal(render(ctx, scene, mode, {}),
                                  render(ctx, scene, mode, {f"{mode}.segments": 1}))
    assert not np.array_equal(render(ctx, scene, mode, {}),
                              render(ctx, scene, mode, {f"{mode}.segments": 2}))


# K = 2 against K = 1, bounds over what was measured: mcguire 0.54x, guertin 0.58x, ue4 0.85x.
BOUND = {"mcguire": 0.7, "guertin": 0.7, "ue4": 0.92}


@pytest.mark.parametrize("mode", ["mcguire", "guertin", "ue4"])
def test_rotation_is_closer_to_the_reference_with_two_segments(ctx, mode):
    """The rolling wheel (its rim turns through a bent path) at 64x36."""
    scene = load_scene(Path(__file__).resolve().parents[1] / "scenes" / "wheel.toml")
    ref = render(ctx, scene, "reference", {"reference.samples": 32})
    err = {k: ((render(ctx, scene, mode, {f"{mode}.segments": k}) - ref) ** 2).mean()
           for k in (1, 2)}
    assert err[2] < BOUND[mode] * err[1], err


def test_ue4_straight_path_is_the_linear_filter(synthetic_frame):
    """Straight uniform paths (o_k = (k/K - 1/2) D): the UE4-style passes with two
    segments reproduce the linear filter (taps, spreads and tiles are the same numbers)."""
    from viewer.render.modes.ue4 import ue4_passes
    rng = np.random.default_rng(5)
    w, h = SIZE
    color = rng.uniform(0, 1, (h, w, 3))
    depth = np.full((h, w), 8.0)
    disp = np.tile(np.array([1.5, -0.75]), (h, w, 1))
    depth[4:11, 9:20] = 2.0
    disp[4:11, 9:20] = [7.25, 3.0]
    out = {}
    for k in (1, 2):
        p = ParamSet()
        p.set("ue4.segments", k)
        p.set("ue4.tile", 8)
        frame = synthetic_frame(SIZE, p, seed=3)
        upload(frame, "color", np.concatenate([color, np.ones((h, w, 1))], axis=2),
               GBUFFER["color"])
        upload(frame, "depth", depth, GBUFFER["depth"])
        upload(frame, "velocity", disp, GBUFFER["velocity"])
        if k == 2:
            upload(frame, "hybrid_path", pack(np.stack([-0.5 * disp, 0 * disp, 0.5 * disp], -2)),
                   GBUFFER["hybrid_path"])
        for ps in ue4_passes():
            ps.allocate(frame)
            ps.execute(frame)
        out[k] = to_image(frame.read("ue4"))[..., :3].astype(np.float64)
    assert np.abs(out[1] - color).max() > 0.05
    close = np.isclose(out[2], out[1], rtol=1e-4, atol=1e-5).all(-1)
    assert close.mean() > 0.98, close.mean()   # (a tap on a pixel edge may round the other way)
