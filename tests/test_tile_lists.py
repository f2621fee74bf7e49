"""Tile lists (viewer/render/modes/hybrid/tile_select.py): the hybrid passes drawn only on listed tiles
give the same pixels as drawn full screen; the tile selection itself against hand values."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import CONFORMANCE
from viewer.render.graph.params import ParamSet
from viewer.render.passes import tile_kernels, tile_runs
from viewer.render.modes.hybrid import tile_select
from viewer.render.modes.hybrid import composite as hybrid_composite
from viewer.render.renderer import Renderer
from world.loader import load_scene

SIZE = (200, 112)


def render_buffers(ctx, scene, p, full_screen: bool, monkeypatch, size=SIZE):
    if full_screen:
        monkeypatch.setattr(tile_select.SelectTiles, "execute", lambda self, frame: None)
    r = Renderer(ctx, scene, size)
    try:
        res = r.render("hybrid", scene.render.time, p)
        # (mask_displacement and mask_edge: the range check's configuration only)
        bufs = {n: r.pool.get(n).read() for n in ("mask_displacement", "mask_edge", "ray_mask",
                                                  "hybrid_tilemax_x", "hybrid_neighbormax",
                                                  "hybrid") if n in r.pool.names()}
        return res, bufs
    finally:
        r.release()
        monkeypatch.undo()


@pytest.mark.parametrize("range_check", [False, True])
@pytest.mark.parametrize("name, composite", [
    ("living_room", "bucket"), ("spinner", "time"), ("thin", "bucket"), ("pan", "time"),
    ("pan", "bucket"), (str(CONFORMANCE / "basic.toml"), "time")])
def test_tiled_passes_equal_full_screen(ctx, monkeypatch, name, composite, range_check):
    # (The "split" composite exists only with tile lists: tests/test_hybrid.py checks it.)
    scene = load_scene(name)
    p = ParamSet()
    p.set("hybrid.composite", composite)
    p.set("hybrid.range_check", range_check)
    tiled, a = render_buffers(ctx, scene, p, False, monkeypatch)
    full, b = render_buffers(ctx, scene, p, True, monkeypatch)
    assert "active_tiles" in tiled.stats and "active_tiles" not in full.stats
    # (The TileMax strip runs only where a tile's D is not all 0: the same strips.)
    assert set(a) == set(b) and ("mask_edge" in a) == range_check
    for n in ("mask_displacement", "mask_edge", "ray_mask", "hybrid_tilemax_x",
              "hybrid_neighbormax"):
        assert a.get(n) == b.get(n), n
    # The composite skips only pixels whose every time sample is their own colour; the
    # full-screen pass averages n equal values there, which may differ in the last bit.
    ha = np.frombuffer(a["hybrid"], np.float32)
    hb = np.frombuffer(b["hybrid"], np.float32)
    np.testing.assert_allclose(ha, hb, rtol=1e-6, atol=1e-7)
    assert tiled.stats["masked_pixels"] == full.stats["masked_pixels"]


def test_moving_tiles_use_the_mask_speed_test():
    longest = np.array([[0.0, 0.99, 1.0, 5.0]], np.float32)
    np.testing.assert_array_equal(tile_select.moving_tiles(longest, 1.0),
                                  [[False, False, True, True]])


def test_active_tiles_reach_half_the_displacement_plus_tolerance():
    tile = 16
    longest = np.zeros((1, 12), np.float32)
    longest[0, 5] = 40.0         # reach 20 + 0.65 + 1 = 21.65 px: gaps 0 and 16 px
    got = tile_select.active_tiles(longest, tile, max_disp=200.0, tolerance=0.65)
    np.testing.assert_array_equal(np.flatnonzero(got[0]), [3, 4, 5, 6, 7])
    # The displacement is clamped to the blur limit before it reaches anything.
    got = tile_select.active_tiles(longest, tile, max_disp=20.0, tolerance=0.65)
    np.testing.assert_array_equal(np.flatnonzero(got[0]), [4, 5, 6])
    # Nothing moves: nothing is active.
    assert not tile_select.active_tiles(np.zeros((3, 3), np.float32), tile, 50.0, 0.65).any()


def quad_rects(tl: tile_runs.TileList, stride: int) -> np.ndarray:
    """The (x0, y0, x1, y1) GL-pixel rectangles of a list's quads, from its vertex buffer."""
    v = np.frombuffer(tl.buffer.read(), np.float32)[:tl.quads * 6 * stride]
    v = v.reshape(tl.quads, 6, stride)[..., :2]
    return np.concatenate([v.min(axis=1), v.max(axis=1)], axis=1).astype(int)


def test_tile_quads_cover_exactly_the_listed_tiles(ctx):
    tl = tile_runs.TileList(ctx)
    try:
        tl.set(np.array([[0, 0], [2, 1]]), 16, (40, 20))
        assert quad_rects(tl, 2).tolist() == [[0, 0, 16, 16], [32, 16, 40, 20]]  # cut at the edge
        # Side by side in a row, then the same run in the next row: one rectangle; the
        # tile that sticks out gets its own.
        tl.set(np.array([[1, 0], [2, 0], [3, 0], [1, 1], [2, 1], [3, 1], [3, 2]]), 16, (100, 50))
        assert sorted(quad_rects(tl, 2).tolist()) == [[16, 0, 64, 32], [48, 32, 64, 48]]
        assert tl.count == 7 and tl.box == (16, 0, 64, 48)
    finally:
        tl.release()


@pytest.mark.parametrize("seed", range(20))
def test_merged_rectangles_cover_each_listed_tile_once(seed):
    rng = np.random.default_rng(seed)
    grid = rng.random((rng.integers(1, 12), rng.integers(1, 30))) < rng.random()
    tiles = np.argwhere(grid)[:, ::-1]                  # (tx, ty)
    rects = tile_kernels.merge_tiles(np.ascontiguousarray(rng.permutation(tiles)))
    cover = np.zeros(grid.shape, int)
    for x0, y0, x1, y1 in rects:
        assert x0 < x1 and y0 < y1
        cover[y0:y1, x0:x1] += 1
    np.testing.assert_array_equal(cover, grid.astype(int))
    # Maximal runs along x: no two rectangles in a row touch end to start with equal rows.
    runs = {(y0, y1, x0) for x0, y0, x1, y1 in rects}
    assert not any((y0, y1, x1) in runs for x0, y0, x1, y1 in rects)


@pytest.mark.parametrize("seed", range(10))
def test_block_quads_map_every_pixel_to_its_tiles_block(seed):
    # Runs of tiles drawn as one quad must still send each pixel to its own tile's block:
    # record = pixel + (block's corner - tile's corner), from the interpolated corners.
    rng = np.random.default_rng(seed)
    tile, per_row, w, h = 8, 4, 90, 50
    grid = rng.random((-(-h // tile), -(-w // tile))) < 0.6
    tiles = np.argwhere(grid)[:, ::-1]
    tiles = np.ascontiguousarray(np.concatenate([tiles, tiles[::3]]))   # a second key's run
    cuts = np.zeros(len(tiles), bool)
    cuts[len(grid.nonzero()[0])] = True
    data, box, first = tile_kernels.block_quads(tiles, tile, w, h, per_row, cuts)
    # Two keys' tiles side by side: a draw per key, so no quad across the cut.
    pair = np.array([[0, 0], [1, 0]])
    assert len(tile_kernels.block_quads(pair, tile, w, h, per_row, np.array([0, 1], bool))[2]) == 2
    assert len(tile_kernels.block_quads(pair, tile, w, h, per_row, np.array([0, 0], bool))[2]) == 1
    quads = data.reshape(-1, 6, 4)
    assert len(quads) < len(tiles) and first[0] == 0 and np.all(np.diff(first) > 0)
    assert len(grid.nonzero()[0]) in first                      # no quad spans the cut
    seen = np.zeros(len(tiles), int)
    for q, corners in enumerate(quads):
        lo, hi = corners[:, :2].min(axis=0), corners[:, :2].max(axis=0)
        offset = corners[0, 2:] - corners[0, :2]
        assert np.all(corners[:, 2:] - corners[:, :2] == offset)   # one affine map a quad
        last = first[q + 1] if q + 1 < len(first) else len(tiles)
        for k in range(first[q], last):
            tx, ty = tiles[k]
            assert lo[0] <= tx * tile < hi[0] and lo[1] <= ty * tile < hi[1]
            block = np.array([k % per_row, k // per_row]) * tile
            np.testing.assert_array_equal(np.array([tx, ty]) * tile + offset, block)
            seen[k] += 1
        # The quad spans exactly its tiles (cut at the screen's edge).
        assert hi[0] == min((tiles[last - 1, 0] + 1) * tile, w) and lo[0] == tiles[first[q], 0] * tile
    assert np.all(seen == 1)


@pytest.mark.parametrize("name", [str(CONFORMANCE / "basic.toml"), "pan"])
def test_partial_clears_leave_nothing_of_the_last_frame(ctx, name):
    # Frames at two times on one renderer: the second one's mask, revealed layers and image
    # equal those of a fresh renderer, though only the boxes written last were cleared
    # (and last frame's tiles not drawn again zeroed: under a moving camera too).
    scene = load_scene(name)
    names = ("mask_displacement", "mask_edge", "ray_mask", "hybrid_back", "hybrid_back_color",
             "hybrid_tilemax_x", "hybrid")
    r = Renderer(ctx, scene, SIZE)
    fresh = Renderer(ctx, scene, SIZE)
    t0 = scene.render.time
    try:
        first = r.render("hybrid", t0, ParamSet())
        second = r.render("hybrid", t0 + 0.5, ParamSet())
        want = fresh.render("hybrid", t0 + 0.5, ParamSet())
        assert first.stats["masked_pixels"] > 0 and second.stats["masked_pixels"] > 0
        for n in names:
            if n in fresh.pool.names():           # (the masks: range check only)
                assert r.pool.get(n).read() == fresh.pool.get(n).read(), n
        assert second.image.tobytes() == want.image.tobytes()
        # Clears are partial: after the frame, only the last points' box is marked.
        x0, y0, x1, y1 = r.pool._written["hybrid_back_color"]
        assert 0 < (x1 - x0) * (y1 - y0) < SIZE[0] * SIZE[1]
    finally:
        r.release()
        fresh.release()


def brute_force_active(longest, tile, max_disp, tolerance):
    """active_tiles by its definition, tile pair by tile pair."""
    h, w = longest.shape
    out = np.zeros((h, w), bool)
    for y in range(h):
        for x in range(w):
            for v in range(h):
                for u in range(w):
                    m = min(float(longest[v, u]), max_disp)
                    gap = max(0, max(abs(x - u), abs(y - v)) - 1) * tile
                    if m > 0 and gap <= 0.5 * m + tolerance + tile_select.MARGIN:
                        out[y, x] = True
    return out


@pytest.mark.parametrize("seed", range(4))
def test_active_tiles_match_their_definition(seed):
    rng = np.random.default_rng(seed)
    longest = np.where(rng.uniform(size=(9, 13)) < 0.1, rng.uniform(0, 120, (9, 13)), 0.0)
    longest = longest.astype(np.float32)
    for max_disp in (20.0, 60.0, 200.0):
        got = tile_select.active_tiles(longest, 8, max_disp, 0.65)
        np.testing.assert_array_equal(got, brute_force_active(longest, 8, max_disp, 0.65))


def test_resize_between_frames_gives_a_fresh_renderers_frame(ctx):
    scene = load_scene(str(CONFORMANCE / "basic.toml"))
    r = Renderer(ctx, scene, SIZE)
    fresh = Renderer(ctx, scene, (150, 90))
    try:
        r.render("hybrid", 0.0, ParamSet())
        r.resize((150, 90))
        got = r.render("hybrid", 0.25, ParamSet())
        want = fresh.render("hybrid", 0.25, ParamSet())
        assert got.stats["masked_pixels"] == want.stats["masked_pixels"] > 0
        assert got.image.tobytes() == want.image.tobytes()
        for n in ("ray_mask", "hybrid_back_color", "hybrid_back"):
            assert r.pool.get(n).read() == fresh.pool.get(n).read(), n
    finally:
        r.release()
        fresh.release()


@pytest.mark.parametrize("seed, tile_bits", [(0, 3), (1, 3), (2, 3), (3, 2)])
def test_record_blocks_match_a_brute_force_packing(seed, tile_bits):
    # reveal_shade's hit records: one tile x tile block per (key, screen tile) in order of
    # (key, tile row, tile column), 4 blocks a row here, each pixel's record at its
    # offset within its tile, -1 there in the tile's other keys' blocks; else zero.
    from viewer.render.modes.hybrid.reveal_kernels import pack_blocks
    rng = np.random.default_rng(seed)
    n, tile, per_row = 500, 1 << tile_bits, 4
    flat = rng.choice(70 * 50, n, replace=False)
    gx, gy = flat % 70, flat // 70
    key = rng.choice([1, 3, 4, 9], n)
    face = rng.integers(-1, 1000, n)
    bary = rng.uniform(0, 1, (n, 2)).astype(np.float32)
    records, block_key, tiles, runs = pack_blocks(gx, gy, key, face, bary, tile_bits, 2)
    cells = sorted({(int(k), int(y) // tile, int(x) // tile) for k, x, y in zip(key, gx, gy)})
    np.testing.assert_array_equal(block_key, [c[0] for c in cells])
    # Each key's run of blocks (key, first, count), in key order.
    firsts = [[c[0] for c in cells].index(k) for k in (1, 3, 4, 9)]
    np.testing.assert_array_equal(runs, [(k, f, sum(c[0] == k for c in cells))
                                         for k, f in zip((1, 3, 4, 9), firsts)])
    np.testing.assert_array_equal(tiles, [(c[2], c[1]) for c in cells])
    want = np.zeros(records.shape, np.float32)
    assert records.shape == (-(-len(cells) // per_row) * tile, per_row * tile, 4)
    index = {c: b for b, c in enumerate(cells)}
    for k in range(n):
        b = index[(key[k], gy[k] // tile, gx[k] // tile)]
        y = (b // per_row) * tile + gy[k] % tile
        x = (b % per_row) * tile + gx[k] % tile
        want[y, x] = (max(face[k], 0), bary[k, 0], bary[k, 1], key[k])
        # The same screen tile's other keys' blocks: -1, "another draw's pixel".
        for other in set(key):
            o = index.get((other, gy[k] // tile, gx[k] // tile))
            if other != key[k] and o is not None:
                want[(o // per_row) * tile + gy[k] % tile, (o % per_row) * tile + gx[k] % tile,
                     3] = -1.0
    assert (want[..., 3] == -1).sum() > 10
    np.testing.assert_array_equal(records, want)


@pytest.mark.parametrize("size", [(320, 180), (640, 360)])
def test_simple_tiles_change_nothing_where_no_outline_is_in_reach(ctx, monkeypatch, size):
    # A moving camera: tiles with no other object within the composite lines' reach draw
    # its SIMPLE variant (the neighbourhood line only where it is the own line); the
    # image equals the full-screen composite's, which never uses it. (Tiles far from any
    # ray-mask edge were not enough: floor and wall touching, no edge between them.)
    scene = load_scene(str(CONFORMANCE / "vase_pan.toml"))
    images = []
    for full_screen in (False, True):
        if full_screen:
            monkeypatch.setattr(tile_select.SelectTiles, "execute", lambda self, frame: None)
        r = Renderer(ctx, scene, size)
        try:
            res = r.render("hybrid", scene.render.time, ParamSet())
        finally:
            r.release()
        images.append(res.image)
        if not full_screen:
            assert res.stats["simple_tiles"] > 0.3 * res.stats["active_tiles"]
    monkeypatch.undo()
    np.testing.assert_allclose(images[0], images[1], rtol=1e-6, atol=1e-7)


def test_range_check_tiles_keep_survivors_far_from_edges(ctx, monkeypatch):
    # A moving camera with edge thresholds few edges pass (the sky's silhouettes only): the
    # ray mask is mostly the displacement test's survivors, many far from any edge, and the
    # range check's tile list (edges in reach, or a survivor) must still hold their tiles.
    scene = load_scene(str(CONFORMANCE / "vase_pan.toml"))
    p = ParamSet()
    p.set("hybrid.range_check", True)
    p.set("hybrid.edge_depth", 10.0)
    p.set("hybrid.edge_normal", 4.0)
    tiled, a = render_buffers(ctx, scene, p, False, monkeypatch)
    full, b = render_buffers(ctx, scene, p, True, monkeypatch)
    assert tiled.stats["range_tiles"] > 0 and tiled.stats["masked_pixels"] > 100
    assert a["ray_mask"] == b["ray_mask"]


def true_boundary_tiles(ids: np.ndarray, tile: int) -> np.ndarray:
    """Tiles (GL rows) holding a pixel whose right or upper neighbour has another id."""
    h, w = ids.shape
    pair = np.zeros((h, w), bool)
    pair[:, :-1] |= ids[:, :-1] != ids[:, 1:]
    pair[:-1, :] |= ids[:-1, :] != ids[1:, :]
    th, tw = -(-h // tile), -(-w // tile)
    out = np.zeros((th, tw), bool)
    ys, xs = np.nonzero(pair)
    out[ys // tile, xs // tile] = True
    return out


def run_motion_tiles(frame, ids, disp):
    """motion_tiles (GL rows: (longest |D|, boundary flag)) of ids and D given in GL rows."""
    from world.conventions import to_image
    from viewer.render.passes.gbuffer import GBUFFER
    h, w = ids.shape
    front = np.dstack([disp, np.full((h, w), 5.0, np.float32), ids]).astype(np.float32)
    frame.pool.texture("hybrid_front", GBUFFER["hybrid_front"])
    frame.write("hybrid_front", to_image(front))
    p = tile_select.MotionTiles()
    p.allocate(frame)
    p.execute(frame)
    tile = tile_runs.FINE
    return np.frombuffer(frame.pool.get("motion_tiles").read(), np.float32).reshape(
        -(-h // tile), -(-w // tile), 2)


@pytest.mark.parametrize("seed", range(3))
def test_motion_tiles_flag_every_id_boundary(synthetic_frame, seed):
    # motion_tiles .y: every tile holding a pixel whose right or upper neighbour shows
    # another object is flagged (conservatively: a few more may be), .x the longest |D|.
    rng = np.random.default_rng(seed)
    w, h, tile = 70, 52, tile_runs.FINE
    ids = np.ones((h, w), np.float32)                     # GL rows
    for _ in range(3):                                    # rectangles of other objects
        x0, y0 = rng.integers(0, w - 8), rng.integers(0, h - 8)
        ids[y0:y0 + rng.integers(3, 30), x0:x0 + rng.integers(3, 30)] = rng.integers(2, 9)
    disp = rng.normal(0, 6, (h, w, 2)).astype(np.float32)
    frame = synthetic_frame((w, h))
    got = run_motion_tiles(frame, ids, disp)
    want = true_boundary_tiles(ids, tile)
    flagged = got[..., 1] != 0
    assert want.any() and not (want & ~flagged).any()
    assert flagged.sum() <= want.sum() + 3
    longest = np.hypot(disp[..., 0], disp[..., 1])
    for ty in range(got.shape[0]):
        for tx in range(got.shape[1]):
            block = longest[ty * tile:(ty + 1) * tile, tx * tile:(tx + 1) * tile]
            np.testing.assert_allclose(got[ty, tx, 0], block.max(), rtol=1e-6)
    # Boundaries that fall exactly between tiles: a row edge at y = 16 (flags tile row 0),
    # a column edge at x = 32 (flags tile column 1), each tile uniform on its own.
    for edge in ("row", "column"):
        ids = np.ones((h, w), np.float32)
        if edge == "row":
            ids[tile:] = 4.0
        else:
            ids[:, 2 * tile:] = 4.0
        got = run_motion_tiles(frame, ids, disp)[..., 1] != 0
        want = true_boundary_tiles(ids, tile)
        np.testing.assert_array_equal(got, want, err_msg=edge)
        assert want.sum() == (got.shape[1] if edge == "row" else got.shape[0])


def test_near_boundary_matches_its_definition():
    rng = np.random.default_rng(4)
    boundary = rng.uniform(size=(9, 12)) < 0.08
    longest = rng.uniform(0, 90, (9, 12)).astype(np.float32)
    got = tile_select.near_boundary(longest, boundary, 16)
    want = np.zeros_like(boundary)
    for y, x in np.ndindex(*boundary.shape):
        for v, u in zip(*np.nonzero(boundary)):
            gap = max(0, max(abs(x - u), abs(y - v)) - 1) * 16
            want[y, x] |= gap <= 0.5 * longest[y, x] + 2.0
    assert want.any() and not want.all()
    np.testing.assert_array_equal(got, want)
    assert not tile_select.near_boundary(longest, np.zeros_like(boundary), 16).any()


def test_displacement_test_runs_only_near_id_boundaries(ctx, monkeypatch):
    # vase_pan: every tile moves, few lie within reach of an object's outline; the masks
    # are those of the full-screen passes all the same.
    scene = load_scene(str(CONFORMANCE / "vase_pan.toml"))
    for size in (SIZE, (400, 224)):
        tiled, a = render_buffers(ctx, scene, ParamSet(), False, monkeypatch, size)
        full, b = render_buffers(ctx, scene, ParamSet(), True, monkeypatch, size)
        assert tiled.stats["surface_tiles"] < tiled.stats["moving_tiles"]
        assert tiled.stats["masked_pixels"] > 100
        assert a["ray_mask"] == b["ray_mask"], size
    assert tiled.stats["surface_tiles"] < 0.5 * tiled.stats["moving_tiles"]


@pytest.mark.parametrize("seed", range(3))
def test_chessboard_distance_is_scipys(seed):
    from scipy.ndimage import distance_transform_cdt
    from viewer.render.passes.tile_kernels import chessboard_distance
    sources = np.random.default_rng(seed).uniform(size=(13, 21)) < 0.04
    sources[5, 7] = True
    np.testing.assert_array_equal(chessboard_distance(sources),
                                  distance_transform_cdt(~sources, metric="chessboard"))


@pytest.mark.parametrize("seed", range(3))
def test_square_max_is_scipys_maximum_filter(seed):
    from scipy.ndimage import maximum_filter
    rng = np.random.default_rng(seed)
    values = (rng.uniform(size=(11, 19)) * (rng.uniform(size=(11, 19)) < 0.1)).astype(np.float32)
    marks = rng.uniform(size=(11, 19)) < 0.05
    for r in (0, 1, 3, 25):
        np.testing.assert_array_equal(tile_kernels.square_max(values, r), maximum_filter(
            values, size=2 * r + 1, mode="constant", cval=0.0))
        np.testing.assert_array_equal(tile_kernels.square_max(marks, r), maximum_filter(
            marks, size=2 * r + 1, mode="constant", cval=False))


def test_pixel_tiles_mark_the_gl_row_tiles_of_image_pixels():
    ij = np.array([[0, 0], [33, 5], [47, 39], [20, 20]], np.int64)      # (i, j), 48x40 image
    got = tile_kernels.pixel_tiles(ij, 3, 3, 16, 40)
    want = np.zeros((3, 3), bool)
    for i, j in ij:
        want[(39 - j) // 16, i // 16] = True
    np.testing.assert_array_equal(got, want)
    assert got[2, 0] and got[2, 2] and got[0, 2] and got.sum() == 4


def test_tile_coords_list_the_true_tiles_row_by_row():
    sel = np.random.default_rng(4).uniform(size=(9, 14)) < 0.3
    ty, tx = np.nonzero(sel)
    np.testing.assert_array_equal(tile_runs.tile_coords(sel), np.stack([tx, ty], axis=1))
    assert tile_runs.tile_coords(np.zeros((3, 4), bool)).shape == (0, 2)


def _line_leaves_object(ids, vn, k, max_len, turn=0.0):
    """Per pixel (GL rows), brute force: does any point of its neighbourhood line, as
    glsl/modes/hybrid/hybrid_bucket.frag taps it (the pixel holding x + 0.5 + s dir, clamped, |s| <=
    |vn| / 2, run where that exceeds 0.5), show another object? turn: the line turned by
    this angle (radians) off vn, as a merged own line may be."""
    h, w = ids.shape
    yy, xx = np.mgrid[0:h, 0:w]
    v = vn[yy // k, xx // k].astype(np.float64)
    length = np.linalg.norm(v, axis=-1)
    r = 0.5 * np.minimum(length, max_len)
    d = v / np.maximum(length, 1e-12)[..., None]
    c, s_ = np.cos(turn), np.sin(turn)
    d = np.stack([c * d[..., 0] - s_ * d[..., 1], s_ * d[..., 0] + c * d[..., 1]], -1)
    leaves = np.zeros((h, w), bool)
    for u in np.linspace(-1.0, 1.0, 801):
        s = u * r
        px = np.clip(np.floor(xx + 0.5 + s * d[..., 0]).astype(int), 0, w - 1)
        py = np.clip(np.floor(yy + 0.5 + s * d[..., 1]).astype(int), 0, h - 1)
        leaves |= ids[py, px] != ids
    return leaves & (r > 0.5)


def _outlines(boundary, vn, tile, k, w, h, max_len, spread=0.0):
    """tile_kernels.outlines_along over every tile, with the composite's margin."""
    return tile_kernels.outlines_along(boundary, np.ones_like(boundary), vn, tile, k, w, h,
                                       max_len, 0.05, spread)


@pytest.mark.parametrize("seed", range(6))
def test_outlines_along_holds_every_tile_whose_line_can_leave_its_object(seed):
    # Random rectangles over a background, random NeighborMax vectors: every pixel whose
    # line reaches another object lies in a tile outlines_along sets, and the directional
    # test leaves out tiles an isotropic reach would keep. With the composite's spread,
    # also every pixel whose line turned by up to the merge angle does.
    rng = np.random.default_rng(seed)
    h, w, tile, k = 72, 104, 8, 12
    ids = np.zeros((h, w), np.int64)
    for n in range(1, 6):
        x0, y0 = rng.integers(0, w - 10), rng.integers(0, h - 10)
        ids[y0:y0 + rng.integers(4, 30), x0:x0 + rng.integers(4, 30)] = n
    vn = np.zeros((-(-h // k), -(-w // k), 2), np.float32)
    vn[..., 0] = rng.uniform(-20, 20, vn.shape[:2])
    vn[..., 1] = rng.uniform(-4, 4, vn.shape[:2])
    vn[0, 0] = 0.0                                         # a still k-tile: no line
    boundary = true_boundary_tiles(ids, tile)
    got = _outlines(boundary, vn, tile, k, w, h, 2.0 * k)
    leaves = _line_leaves_object(ids, vn, k, 2.0 * k)
    yy, xx = np.nonzero(leaves)
    assert len(yy) > 100
    assert got[yy // tile, xx // tile].all()
    assert not got.all() and got.sum() < boundary.sum() * 9
    angle = np.radians(hybrid_composite.MERGE_ANGLE_DEG)
    spread = _outlines(boundary, vn, tile, k, w, h, 2.0 * k, np.sin(angle))
    assert (spread >= got).all()
    turned = np.zeros_like(leaves)
    for turn in np.linspace(-angle, angle, 9):
        turned |= _line_leaves_object(ids, vn, k, 2.0 * k, turn)
    yy, xx = np.nonzero(turned)
    assert spread[yy // tile, xx // tile].all()


def test_outlines_along_follows_the_line_direction():
    # A horizontal outline (object above the middle row) and horizontal motion: the lines
    # never cross it, so only the row of tiles holding it is set; vertical motion of 16 px
    # reaches 8 px, a tile: the rows beside it too, and no others.
    h, w, tile, k = 64, 64, 8, 16
    ids = np.zeros((h, w), np.int64)
    ids[32:, :] = 1
    boundary = true_boundary_tiles(ids, tile)
    assert boundary[3].all() and boundary.sum() == 8       # pairs (31, 32): row of tiles 3
    vn = np.zeros((h // k, w // k, 2), np.float32)
    vn[..., 0] = 16.0
    got = _outlines(boundary, vn, tile, k, w, h, 32.0)
    np.testing.assert_array_equal(got, boundary)
    # Lines turned by up to the merge angle reach 8 sin(7 deg) = 0.97 px across: over the
    # outline from the row of pixels above it (tile row 4) too; the kernel knows only
    # that the outline lies in tile row 3, so it also takes the row below (within 1 px of
    # that tile's box), and no others.
    angle = np.radians(hybrid_composite.MERGE_ANGLE_DEG)
    spread = _outlines(boundary, vn, tile, k, w, h, 32.0, np.sin(angle))
    np.testing.assert_array_equal(np.nonzero(spread.all(axis=1))[0], [2, 3, 4])
    assert spread.sum() == 24
    yy, _ = np.nonzero(_line_leaves_object(ids, vn, k, 32.0, angle))
    assert set(yy // tile) == {3, 4}
    vn = vn[..., ::-1].copy()
    got = _outlines(boundary, vn, tile, k, w, h, 32.0)
    np.testing.assert_array_equal(np.nonzero(got.all(axis=1))[0], [2, 3, 4])
    todo = np.zeros_like(boundary)
    todo[:, :3] = True                                     # only these tiles are decided
    np.testing.assert_array_equal(tile_kernels.outlines_along(
        boundary, todo, vn, tile, k, w, h, 32.0, 0.05), got & todo)
    assert got.sum() == 24
    # A screen border: a line running off the left edge is clamped there, so an outline
    # in the border column reaches every tile whose line leaves the screen.
    ids = np.zeros((h, w), np.int64)
    ids[40:48, 0] = 1
    boundary = true_boundary_tiles(ids, tile)
    vn = np.zeros((h // k, w // k, 2), np.float32)
    vn[..., 0] = 16.0
    got = _outlines(boundary, vn, tile, k, w, h, 32.0)
    leaves = _line_leaves_object(ids, vn, k, 32.0)
    yy, xx = np.nonzero(leaves)
    assert got[yy // tile, xx // tile].all() and got[:, 1].sum() == 2
    # A line that leaves the screen at the bottom, clamped onto an object further along the
    # bottom row: its segment never meets that object's boundary tiles, only their
    # extension past the screen's edge does.
    ids = np.zeros((h, w), np.int64)
    ids[0:4, 32:41] = 1
    vn = np.zeros((h // k, w // k, 2), np.float32)
    vn[0, 0] = (60.0 / np.sqrt(2.0), -60.0 / np.sqrt(2.0))
    assert _line_leaves_object(ids, vn, k, 64.0)[4, 14]
    boundary = true_boundary_tiles(ids, tile)
    assert not boundary[0, :3].any() and not boundary[1:].any()
    assert _outlines(boundary, vn, tile, k, w, h, 64.0)[0, 1]
