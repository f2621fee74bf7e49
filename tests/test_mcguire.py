"""McGuire 2012 (mode `mcguire`): each pass on tiny synthetic buffers against the numpy
statement of the formulas in tests/numpy_mcguire.py, analytic cases (moving bar, uniform
translation, static scene), determinism, and the whole mode against the reference.

Arrays here are in GL orientation (row 0 at the bottom, velocity y up) like the numpy
reference; `upload`/`download` flip to and from the frames' image orientation.
"""
from __future__ import annotations

import numpy as np
import pytest

import numpy_mcguire as nm
from conftest import CONFORMANCE
from glsl import DIR as GLSL_DIR
from world.conventions import to_image
from viewer.render.graph.params import ParamSet
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.passes.gbuffer import GBUFFER
from viewer.render.modes.mcguire import EARLY_OUT_PX, JITTER_STREAM, mcguire_passes
from viewer.render.passes.tiles import TileMaxPass
from viewer.render.modes.reference import REGIONS

SIZE = (32, 16)          # W, H


# ---- helpers --------------------------------------------------------------------------------

def params(max_radius=None, group="mcguire", **kw):
    """blur.max_radius and GROUP.key = value for each keyword."""
    p = ParamSet()
    if max_radius is not None:
        p.set("blur.max_radius", max_radius)
    for key, value in kw.items():
        p.set(f"{group}.{key}", value)
    return p


def upload(frame, color, depth, displacement):
    """G-buffer inputs, GL orientation: colour (H,W,3), depth (H,W), displacement (H,W,2)."""
    rgba = np.concatenate([color, np.ones(color.shape[:2] + (1,))], axis=2)
    for name, a in (("color", rgba), ("depth", depth), ("velocity", displacement)):
        frame.pool.texture(name, GBUFFER[name])
        frame.write(name, to_image(np.asarray(a, np.float32)))


def run(frame):
    for p in mcguire_passes():
        p.allocate(frame)
        p.execute(frame)
    return download(frame, "mcguire")[..., :3].astype(np.float64)


def download(frame, name):
    return to_image(frame.read(name))


def k_of(frame):
    return max_radius_px(frame)


def random_velocities(rng, h, w, scale):
    """Displacements with distinct magnitudes (no ties for the longest-vector choice)."""
    mags = rng.permutation(np.linspace(0.1, scale, h * w)).reshape(h, w)
    ang = rng.uniform(0, 2 * np.pi, (h, w))
    return np.stack([mags * np.cos(ang), mags * np.sin(ang)], -1)


def two_layer_scene(rng, h, w):
    """A random layered scene: a near slab moving over a far textured plane moving slowly."""
    color = rng.uniform(0, 1, (h, w, 3))
    depth = np.full((h, w), 8.0)
    disp = np.tile(np.array([1.3, -0.7]), (h, w, 1))
    depth[4:11, 9:20] = 2.0 + 0.01 * rng.uniform(size=(7, 11))
    disp[4:11, 9:20] = [7.3, 2.9]
    depth[0, 0:3] = 1e9                      # background pixels (BACKGROUND_DEPTH)
    disp[0, 0:3] = 0.0
    return color, depth, disp


# ---- the numpy reference on hand-computed values ---------------------------------------------

def test_reference_weights_by_hand():
    assert nm.cone(1.0, 2.0) == 0.5 and nm.cone(3.0, 2.0) == 0.0
    assert nm.cylinder(0.94, 1.0) == 1.0 and nm.cylinder(1.06, 1.0) == 0.0
    assert nm.cylinder(1.0, 1.0) == pytest.approx(0.5)
    # positive depth: nearer A is in front; farther by soft_z or more is not
    assert nm.front(2.0, 5.0, 0.1) == 1.0 and nm.front(5.0, 2.0, 0.1) == 0.0
    assert nm.front(2.05, 2.0, 0.1) == pytest.approx(0.5)


def test_reference_gather_by_hand():
    # 5x1, v = (2, 0) everywhere, S = 3, no jitter: taps t = -1/2, +1/2 land on x +- 1 at
    # distance 1; cone(1, 2) = 1/2 from each of the two depth cases, 2 cyl cyl = 2: a = 3.
    c = np.arange(15, dtype=float).reshape(1, 5, 3)
    v = np.tile(np.float32([2.0, 0.0]), (1, 5, 1))
    out, amb = nm.gather(c, np.ones((1, 5)), v, v[:, :1], k=5, samples=3, jitter=0.0)
    expect = (0.5 * c[0, 2] + 3 * c[0, 1] + 3 * c[0, 3]) / 6.5
    np.testing.assert_allclose(out[0, 2], expect, rtol=1e-12)
    assert not amb.any()


def test_reference_clamp_and_tiles_by_hand():
    d = np.array([[[0, 0], [0.2, 0], [0, -6], [30, 40]]], float)
    v = nm.clamp_velocity(d, k=4)
    np.testing.assert_allclose(v[0], [[0, 0], [0.5, 0], [0, -3], [2.4, 3.2]], rtol=1e-6)
    t = nm.tilemax(v, 3)
    assert t.shape == (1, 2, 2)
    np.testing.assert_array_equal(t[0], np.float32([[0, -3], [2.4, 3.2]]))
    np.testing.assert_array_equal(nm.neighbormax(t)[0], np.float32([[2.4, 3.2], [2.4, 3.2]]))


# ---- velocity setup --------------------------------------------------------------------------

def test_velocity_clamp(synthetic_frame):
    rng = np.random.default_rng(1)
    w, h = SIZE
    frame = synthetic_frame(SIZE, params(max_radius=0.25))      # k = 8
    k = k_of(frame)
    assert k == 8
    disp = random_velocities(rng, h, w, 40.0)
    disp[0, :4] = 0.0                                # exactly still
    disp[1, :4] = [[1e-20, 0], [0, -3e-30], [0.3, 0.4], [-16, 0]]   # tiny, tiny, <0.5, =k
    upload(frame, np.zeros((h, w, 3)), np.ones((h, w)), disp)
    p = mcguire_passes()[0]
    p.allocate(frame), p.execute(frame)
    v = download(frame, "mcguire_velocity")
    ref = nm.clamp_velocity(disp, k)
    np.testing.assert_allclose(v, ref, rtol=2e-6, atol=1e-7)
    assert np.all(v[0, :4] == 0.0)
    mag = np.hypot(v[..., 0], v[..., 1])
    assert np.all(mag[disp.any(-1)] >= 0.5 - 1e-6) and mag.max() <= k + 1e-5
    np.testing.assert_allclose(v[1, :4], [[0.5, 0], [0, -0.5], [0.3, 0.4], [-8, 0]], rtol=1e-6)


# ---- tiles -----------------------------------------------------------------------------------

@pytest.mark.parametrize("size,max_radius", [((32, 16), 0.15), ((29, 13), 0.1), ((32, 16), 0.125)])
def test_tilemax_and_neighbormax(synthetic_frame, size, max_radius):
    """Separable TileMax (partial tiles where the size is not a multiple of k) and
    NeighborMax copy exactly the vectors the formulas pick."""
    rng = np.random.default_rng(2)
    w, h = size
    frame = synthetic_frame(size, params(max_radius=max_radius))
    k = k_of(frame)
    disp = random_velocities(rng, h, w, 2.0 * k)
    upload(frame, np.zeros((h, w, 3)), np.ones((h, w)), disp)
    for p in mcguire_passes()[:4]:
        p.allocate(frame), p.execute(frame)
    v = download(frame, "mcguire_velocity")
    strip, tiles = download(frame, "mcguire_tilemax_x"), download(frame, "mcguire_tilemax")
    nmax = download(frame, "mcguire_neighbormax")
    tw, th = -(-w // k), -(-h // k)
    assert strip.shape == (h, tw, 2) and tiles.shape == (th, tw, 2) and nmax.shape == (th, tw, 2)
    np.testing.assert_array_equal(strip, nm.tilemax_x(v, k))
    np.testing.assert_array_equal(tiles, nm.tilemax_y(strip, k))
    np.testing.assert_array_equal(nmax, nm.neighbormax(tiles))
    # and the separable result is the longest vector of each whole tile
    for ty in range(th):
        for tx in range(tw):
            block = v[ty * k:(ty + 1) * k, tx * k:(tx + 1) * k].reshape(-1, 2)
            assert np.hypot(*tiles[ty, tx]) == np.hypot(block[:, 0], block[:, 1]).max()


def test_neighbormax_centre_wins_ties_and_reaches_one_tile(synthetic_frame):
    frame = synthetic_frame((4 * 3, 4 * 3), params(max_radius=1 / 12))     # k = 1: 12x12 tiles
    assert k_of(frame) == 1
    v = np.zeros((12, 12, 2))
    v[5, 5] = [0.75, 0.0]            # within k = 1, so the clamp keeps them
    v[5, 6] = [0.0, 0.75]            # same length, neighbour of (5, 5)
    upload(frame, np.zeros((12, 12, 3)), np.ones((12, 12)), 2 * v)
    for p in mcguire_passes()[:4]:
        p.allocate(frame), p.execute(frame)
    nmax = download(frame, "mcguire_neighbormax")
    np.testing.assert_array_equal(nmax[5, 5], [0.75, 0])
    np.testing.assert_array_equal(nmax[5, 6], [0, 0.75])
    assert np.all(nmax[3, :] == 0) and np.all(nmax[:, 8] == 0)   # two tiles away: untouched
    np.testing.assert_array_equal(nmax[4, 4], [0.75, 0])


def test_tilemax_pass_rejects_bad_axis():
    with pytest.raises(ValueError):
        TileMaxPass("a", "b", "z")


# ---- noise -----------------------------------------------------------------------------------

def test_hash_port_matches_glsl(ctx):
    src = ("#version 330 core\n" + (GLSL_DIR / "graph/noise.glsl").read_text() +
           "\nuniform uint u_stream;\nout float o;\n"
           "void main() { o = hash01(ivec2(gl_FragCoord.xy), u_stream); }\n")
    vs = (GLSL_DIR / "graph/fullscreen.vert").read_text()
    prog = ctx.program(vertex_shader=vs, fragment_shader=src)
    tex = ctx.texture((37, 11), 1, dtype="f4")
    fbo = ctx.framebuffer([tex])
    vao = ctx.vertex_array(prog, [])
    previous = ctx.fbo                 # rebound before release: a deleted bound fbo breaks
    try:                               # the next draw
        for seed, stream in ((0, 0), (12345, JITTER_STREAM), (0xFFFFFFFF, 7)):
            prog["u_seed"].value, prog["u_stream"].value = seed, stream
            fbo.use()
            vao.render(vertices=3)
            got = np.frombuffer(tex.read(), np.float32).reshape(11, 37)
            ys, xs = np.mgrid[0:11, 0:37]
            np.testing.assert_array_equal(got, nm.hash01(xs, ys, seed, stream))
    finally:
        previous.use()
        vao.release(), fbo.release(), tex.release(), prog.release()


# ---- the gather ------------------------------------------------------------------------------

@pytest.mark.parametrize("jitter,seed,samples,kappa", [(0.0, 0, 15, 0.0), (1.0, 7, 15, 0.0),
                                                       (0.6, 3, 9, 0.0), (1.0, 1, 15, 40.0)])
def test_gather_matches_reference(synthetic_frame, jitter, seed, samples, kappa):
    rng = np.random.default_rng(3)
    w, h = SIZE
    frame = synthetic_frame(SIZE, params(max_radius=0.25, jitter=jitter, samples=samples,
                                         centre_kappa=kappa), seed=seed)
    color, depth, disp = two_layer_scene(rng, h, w)
    upload(frame, color, depth, disp)
    out = run(frame)
    ref, amb = nm.mcguire(color, depth, disp, k_of(frame), samples=samples, soft_z=0.1,
                          jitter=jitter, seed=seed, stream=JITTER_STREAM, kappa=kappa,
                          early_out=EARLY_OUT_PX)
    assert amb.mean() < 0.2                  # the comparison covers most pixels
    np.testing.assert_allclose(out[~amb], ref[~amb], rtol=1e-4, atol=1e-5)


def test_soft_z_extent_changes_the_compare(synthetic_frame):
    """Two moving layers 0.3 m apart: with SOFT_Z_EXTENT 1 m they partly blend as one
    surface, with 0.05 m the far one is behind; both as the formulas say. (Both move more
    than a pixel, or the cone of the slower one is zero at every tap.)"""
    rng = np.random.default_rng(4)
    w, h = SIZE
    color = rng.uniform(0, 1, (h, w, 3))
    depth = np.where(np.arange(w)[None, :] < 16, 3.0, 3.3) * np.ones((h, 1))
    disp = np.tile([6.0, 0.0], (h, w, 1))
    disp[:, 16:] = [4.0, 0.0]
    outs = []
    for sz in (1.0, 0.05):
        frame = synthetic_frame(SIZE, params(max_radius=0.25, soft_z_extent=sz, jitter=0.0))
        upload(frame, color, depth, disp)
        out = run(frame)
        ref, amb = nm.mcguire(color, depth, disp, 8, soft_z=sz, jitter=0.0)
        np.testing.assert_allclose(out[~amb], ref[~amb], rtol=1e-4, atol=1e-5)
        outs.append(out)
    assert np.abs(outs[0] - outs[1]).max() > 0.01


# ---- analytic behaviour ----------------------------------------------------------------------

BAR, BACK = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.2, 1.0])


def test_moving_bar_smears_over_static_background(synthetic_frame):
    """Outer blur: a near bar moving right over a static far background. The background
    beside the bar takes bar colour, fading with distance, and nothing beyond the bar's
    reach changes; the bar itself stays mostly bar (only its own inner blur lets the
    background in). A depth compare with the sign the wrong way round gives no smear."""
    w, h = SIZE
    frame = synthetic_frame(SIZE, params(max_radius=0.25, jitter=0.0))   # k = 8
    color = np.tile(BACK, (h, w, 1))
    depth = np.full((h, w), 10.0)
    disp = np.zeros((h, w, 2))
    color[:, 12:20], depth[:, 12:20], disp[:, 12:20] = BAR, 2.0, [12.0, 0.0]   # v = 6 px
    upload(frame, color, depth, disp)
    out = run(frame)
    ref, amb = nm.mcguire(color, depth, disp, 8, jitter=0.0)
    np.testing.assert_allclose(out[~amb], ref[~amb], rtol=1e-4, atol=1e-5)
    bar = out[8, :, 0]                        # red = bar coverage (background has no red)
    left, right = bar[11:6:-1], bar[20:25]    # 1..5 px outside each edge
    assert np.all(left > 0.02) and np.all(right > 0.02)
    assert left[0] > 0.2 and right[0] > 0.2
    assert np.all(np.diff(left) < 0) and np.all(np.diff(right) < 0)
    np.testing.assert_allclose(out[:, :5], color[:, :5], atol=1e-6)   # out of the bar's reach
    assert np.all(bar[12:20] >= 0.5)
    assert np.all(out[8, 12:20, 2] < 0.5)     # background blue never dominates the bar


def test_static_bar_is_not_smeared_by_moving_background(synthetic_frame):
    """The reverse case: a static near bar over a far background moving fast. The bar
    stays exactly the bar and the background next to it takes no bar colour."""
    rng = np.random.default_rng(5)
    w, h = SIZE
    frame = synthetic_frame(SIZE, params(max_radius=0.25))
    color = np.zeros((h, w, 3))
    color[..., 1:] = rng.uniform(0.2, 1.0, (h, w, 2))      # background: no red
    depth = np.full((h, w), 10.0)
    disp = np.tile([14.0, 3.0], (h, w, 1))
    color[:, 12:20], depth[:, 12:20], disp[:, 12:20] = BAR, 2.0, 0.0
    upload(frame, color, depth, disp)
    out = run(frame)
    np.testing.assert_allclose(out[:, 12:20], color[:, 12:20], atol=1e-6)
    assert np.all(out[:, :12, 0] == 0) and np.all(out[:, 20:, 0] == 0)
    assert np.abs(out[:, :12] - color[:, :12]).max() > 0.05      # the background did blur


def box_blur_1d(row: np.ndarray, radius: float) -> np.ndarray:
    """Mean of the pixel-constant signal over [c - radius, c + radius] around each centre."""
    n = len(row)
    cum = np.concatenate([[0.0], np.cumsum(row)])

    def integral(x):                      # integral of the signal over [0, x]
        i = np.clip(np.floor(x).astype(int), 0, n - 1)
        return cum[i] + (x - i) * row[i]

    c = np.arange(n) + 0.5
    return (integral(c + radius) - integral(c - radius)) / (2 * radius)


@pytest.mark.parametrize("axis", [0, 1])
def test_uniform_translation_is_a_box_blur_of_length_D(synthetic_frame, axis):
    """A textured plane translating by D: away from the borders the result is a box blur of
    length |D| up to the filter's own shape. Its taps weigh 4 - 2|t| (two cones plus the
    cylinder term), a trapezoid against the box, which bends an edge's ramp by up to ~0.04
    of the contrast; rounding taps to pixel centres adds up to 0.5/|D| (0.056) and the
    jitter moves the taps by up to one spacing. So 0.12 of the contrast bounds a pixel and
    0.04 the mean (30 seeds of the numpy filter: at most 0.082 and 0.032). The support is
    checked apart: untouched beyond |D|/2 of an edge, mixed well inside it."""
    w, h = (48, 16) if axis == 0 else (24, 48)
    frame = synthetic_frame((w, h), params(max_radius=4.5 / w), seed=11)
    k = k_of(frame)
    assert k == 5
    n = w if axis == 0 else h
    stripes = np.where((np.arange(n) // 12) % 2 == 0, 0.1, 0.9)
    d = 9.0                                    # |D|, half vector 4.5 < k
    if axis == 0:
        color = np.tile(stripes[None, :, None], (h, 1, 3))
        disp = np.tile([d, 0.0], (h, w, 1))
    else:
        color = np.tile(stripes[:, None, None], (1, w, 3))
        disp = np.tile([0.0, -d], (h, w, 1))
    upload(frame, color, np.full((h, w), 4.0), disp)
    out = run(frame)
    got = out[h // 2, :, 0] if axis == 0 else out[:, w // 2, 0]
    box = box_blur_1d(stripes, d / 2)
    inner = slice(6, n - 6)
    err = np.abs(got[inner] - box[inner])
    assert err.max() < 0.12 * 0.8 and err.mean() < 0.04 * 0.8
    # out of an edge's reach the colour is untouched; well within it, it is a mix
    flat = np.abs(box - stripes) < 1e-9
    np.testing.assert_allclose(got[flat], stripes[flat], atol=1e-5)
    mixed = np.abs(box - stripes) > 0.1 * 0.8
    assert np.all(np.abs(got - stripes)[mixed] > 0.05 * 0.8)


def assert_still_scene_unchanged(synthetic_frame, params, run):
    """A scene where nothing moves comes out of `run` as its colour, exactly."""
    rng = np.random.default_rng(6)
    w, h = SIZE
    frame = synthetic_frame(SIZE, params)
    color = rng.uniform(0, 4, (h, w, 3))
    upload(frame, color, rng.uniform(1, 20, (h, w)), np.zeros((h, w, 2)))
    out = run(frame)
    np.testing.assert_array_equal(out.astype(np.float32), color.astype(np.float32))


def test_static_scene_is_unchanged_exactly(synthetic_frame):
    assert_still_scene_unchanged(synthetic_frame, params(), run)


def images_per_seed(synthetic_frame, params, run, output, seeds=(5, 5, 6)):
    """The bytes of `output` after `run` on the two-layer scene, one frame per seed."""
    rng = np.random.default_rng(7)
    w, h = SIZE
    color, depth, disp = two_layer_scene(rng, h, w)
    images = []
    for seed in seeds:
        frame = synthetic_frame(SIZE, params, seed=seed)
        upload(frame, color, depth, disp)
        run(frame)
        images.append(frame.pool.get(output).read())
    return images


def test_deterministic_per_seed(synthetic_frame):
    images = images_per_seed(synthetic_frame, params(max_radius=0.25), run, "mcguire")
    assert images[0] == images[1]
    assert images[0] != images[2]


# ---- the whole mode --------------------------------------------------------------------------

def render_basic(ctx, modes, size=(160, 90)):
    """The conformance scene `basic` at its time: the reference (with regions), each of
    `modes` at seed 1 (linear images) and the description of each mode's pipeline."""
    from viewer.render.renderer import Renderer
    from world.loader import load_scene
    scene = load_scene(CONFORMANCE / "basic.toml")
    r = Renderer(ctx, scene, size)
    try:
        t = scene.render.time
        ref = r.render("reference", t, record_visibility=True)
        images = {m: r.render(m, t, seed=1).image for m in modes}
        names = {m: r.pipeline(m).describe() for m in modes}
    finally:
        r.release()
    return ref, images, names


def test_mode_beats_off_in_outer_blur_on_basic(ctx):
    from viewer.render.modes.regions import OUTER
    from viewer.eval.metrics import image_metrics
    ref, images, names = render_basic(ctx, ("off", "mcguire"))
    off, mc = images["off"], images["mcguire"]
    region = ref.host[REGIONS]
    outer = region == OUTER
    assert outer.sum() > 50
    err = {k: float(((img - ref.image) ** 2)[outer].mean()) for k, img in
           (("off", off), ("mcguire", mc))}
    assert err["mcguire"] < 0.4 * err["off"]          # measured: 0.2
    m_off = image_metrics(off, ref.image, region)["outer"]["flip"]
    m_mc = image_metrics(mc, ref.image, region)["outer"]["flip"]
    assert m_mc < m_off
    static = region == 0
    assert np.abs(mc - off)[static].mean() < 0.003         # static pixels are left alone
    for tex in ("mcguire_velocity", "mcguire_tilemax_x", "mcguire_tilemax",
                "mcguire_neighbormax", "mcguire"):
        assert tex in names["mcguire"]
