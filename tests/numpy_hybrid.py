"""A numpy statement of the hybrid mode's GPU passes (viewer/render/modes/hybrid/mask.py and
viewer/render/modes/hybrid/composite.py), the oracle for the GLSL.

Arrays are in GL orientation: row 0 is the BOTTOM row, index [y, x], displacements in GL
window axes (x right, y up), as the fragment shaders see them. Tests flip with
world.conventions.to_image when reading or writing frames. Depth is positive linear view
depth; ids are uint (0 = background). Displacements are the full motion over the exposure.

Positions that decide a discrete outcome (which pixel a probe reads) are computed in
float32 with the shader's order of operations.
"""
from __future__ import annotations

import numpy as np

from viewer.render.modes.hybrid.composite import MERGE_COS   # (a setting, not logic)

F32 = np.float32


def probe(x: int, y: int, offset, size) -> tuple[int, int]:
    """The pixel nearest to pixel (x, y)'s centre + offset, clamped to the screen."""
    w, h = size
    px = int(np.floor(F32(x) + F32(0.5) + F32(offset[0])))
    py = int(np.floor(F32(y) + F32(0.5) + F32(offset[1])))
    return min(max(px, 0), w - 1), min(max(py, 0), h - 1)


def _length(v) -> float:
    v = np.asarray(v, dtype=F32)
    return float(np.sqrt(F32(v[0]) * F32(v[0]) + F32(v[1]) * F32(v[1])))


# ---- ray mask --------------------------------------------------------------------------------

def displacement_test(depth, ids, disp, min_speed: float, threshold: float,
                      relative_only: bool = False):
    """Step 1: (mask uint8 (H,W), relative displacement (H,W,2)). relative_only: the
    default mask's test (glsl/modes/hybrid/raymask_displacement.frag STEP 3), the probes along the
    relative displacement alone decide; the full displacement's only find D_bg."""
    h, w = ids.shape
    disp = np.asarray(disp, dtype=F32)
    mask = np.zeros((h, w), np.uint8)
    rel = disp.copy()
    for y in range(h):
        for x in range(w):
            d = disp[y, x]
            own, z = ids[y, x], depth[y, x]
            if own == 0 or _length(d) < min_speed:
                continue

            def uncovers(offset):
                px, py = probe(x, y, offset, (w, h))
                far = F32(depth[py, px]) > F32(z) * F32(1.0 + threshold)
                return (ids[py, px] != own and far), disp[py, px]

            found = False
            for s in (-1, 1):
                hit, vb = uncovers(F32(0.5 * s) * d)
                if hit:
                    if not relative_only:
                        mask[y, x] = 1
                    if not found:
                        rel[y, x] = d - vb
                        found = True
            if found:
                for s in (-1, 1):
                    if uncovers(F32(0.5 * s) * rel[y, x])[0]:
                        mask[y, x] = 1
    return mask, rel


SOBEL_X = np.array([[-1, 0, 1], [-2, 0, 2], [-1, 0, 1]], dtype=np.float64)   # [dy+1, dx+1]


def sobel(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sobel gradients (divided by 4) of an (H,W) or (H,W,C) array, edges clamped."""
    h, w = a.shape[:2]
    pad = np.pad(a, [(1, 1), (1, 1)] + [(0, 0)] * (a.ndim - 2), mode="edge")
    gx = np.zeros(a.shape)
    gy = np.zeros(a.shape)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            win = pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
            gx = gx + SOBEL_X[dy + 1, dx + 1] * win
            gy = gy + SOBEL_X[dx + 1, dy + 1] * win     # the transposed kernel
    return 0.25 * gx, 0.25 * gy


def stored_log_depth(depth) -> np.ndarray:
    """log depth as the hybrid G-buffer stores it for the edge test: the normal target's
    w, half precision (glsl/passes/gbuffer_outputs.glsl)."""
    return np.log(np.maximum(np.asarray(depth, np.float32), np.float32(1e-6))).astype(np.float16)


def edge_test(dmask, depth, normal, edge_depth: float, edge_normal: float) -> np.ndarray:
    """Step 2: survivors of step 1 on a log-depth or normal Sobel edge. uint8 (H,W)."""
    gx, gy = sobel(stored_log_depth(depth).astype(np.float64))
    g_depth = np.hypot(gx, gy)
    nx, ny = sobel(np.asarray(normal, np.float64)[..., :3])
    g_normal = np.sqrt((nx * nx).sum(-1) + (ny * ny).sum(-1))
    edge = (g_depth > edge_depth) | (g_normal > edge_normal)
    return ((dmask != 0) & edge).astype(np.uint8)


def range_check(dmask, edge, ids, disp, rel, min_speed: float, relative_reach: float,
                max_reach: float) -> np.ndarray:
    """Step 3: the ray mask, the own id where masked. uint32 (H,W)."""
    h, w = ids.shape
    disp = np.asarray(disp, dtype=F32)
    out = np.zeros((h, w), np.uint32)
    for y in range(h):
        for x in range(w):
            own, d = ids[y, x], disp[y, x]
            ln = _length(d)
            if own == 0 or ln < min_speed:
                continue
            if dmask[y, x]:
                out[y, x] = own
                continue
            half = 0.5 * ln
            direction = d / F32(ln)
            steps = int(np.ceil(min(max_reach, relative_reach * half)))
            done = False
            for i in range(steps + 1):
                for s in (-1, 1):
                    px, py = probe(x, y, F32(s * i) * direction, (w, h))
                    if not edge[py, px] or ids[py, px] != own:
                        continue
                    reach = max(half, 0.5 * _length(rel[py, px]))
                    if i <= min(reach, max_reach):
                        out[y, x] = own
                        done = True
                        break
                if done:
                    break
    return out


def tile_summary(mask, tile: int) -> np.ndarray:
    """ray_mask_tiles (hybrid/composite.py mask_tiles): per k x k tile (GL origin), (0, 1 if any
    pixel is masked)."""
    h, w = mask.shape
    th, tw = -(-h // tile), -(-w // tile)
    out = np.zeros((th, tw, 2), np.float32)
    for ty in range(th):
        for tx in range(tw):
            if mask[ty * tile:(ty + 1) * tile, tx * tile:(tx + 1) * tile].any():
                out[ty, tx, 1] = 1.0
    return out


def ray_mask(depth, ids, disp, normal, *, min_speed=1.0, threshold=0.01, edge_depth=0.05,
             edge_normal=0.3, relative_reach=2.0, max_reach=16.0):
    """All three steps: (mask_displacement, mask_relative, mask_edge, ray_mask)."""
    dm, rel = displacement_test(depth, ids, disp, min_speed, threshold)
    edge = edge_test(dm, depth, normal, edge_depth, edge_normal)
    return dm, rel, edge, range_check(dm, edge, ids, disp, rel, min_speed, relative_reach,
                                      max_reach)


# ---- composite ---------------------------------------------------------------------------------

def clamp_length(d: np.ndarray, limit: float) -> np.ndarray:
    d = np.asarray(d, dtype=np.float64)
    ln = np.hypot(d[..., 0], d[..., 1])
    scale = np.where(ln > limit, limit / np.where(ln > 0, ln, 1.0), 1.0)
    return d * scale[..., None]


def pack_layers(color, depth, disp, rev_color, rev_depth, rev_disp, max_disp, ids=None,
                rev_ids=None):
    """One revealed layer as glsl/modes/hybrid/hybrid_layers.glsl reads it: front and back as (motion
    (H,W,4), colour); the front motion's 4th channel is the object id, the back's 1 + the
    revealed id where revealed, else 0 (and there the back reads the front's values)."""
    ids = np.zeros(depth.shape) if ids is None else ids
    front = np.concatenate([clamp_length(disp, max_disp), depth[..., None],
                            np.asarray(ids, np.float64)[..., None]], axis=-1)
    revealed = rev_color[..., 3] > 0.5
    back = front.copy()
    back[revealed, :2] = clamp_length(rev_disp, max_disp)[revealed]
    back[revealed, 2] = rev_depth[revealed]
    rev_ids = np.zeros(depth.shape) if rev_ids is None else np.asarray(rev_ids, np.float64)
    back[..., 3] = np.where(revealed, 1.0 + rev_ids, 0.0)
    back_color = np.where(revealed[..., None], rev_color[..., :3], color[..., :3])
    return front, color[..., :3], back, back_color


def stored_back(back, back_color):
    """The back layer as reveal_shade stores it: the packed texel and (colour, 1) where
    revealed, zeros elsewhere (the shader falls back to the front there)."""
    revealed = back[..., 3] > 0.5
    motion = np.where(revealed[..., None], back, 0.0)
    colour = np.where(revealed[..., None], np.concatenate(
        [back_color, np.ones(back_color.shape[:2] + (1,))], axis=-1), 0.0)
    return motion, colour


def walk(motion, centre, u, seed, iterations, tolerance):
    """(residual, pixel, motion texel): the pixel whose surface lands nearest to the centre
    at time u on the fixed-point walk p <- centre - u D(p), over all its steps."""
    h, w = motion.shape[:2]
    p = centre - u * np.asarray(seed)
    best = (np.inf, None, None)
    for _ in range(iterations + 1):
        raw = np.floor(p).astype(int)
        q = np.clip(raw, 0, [w - 1, h - 1])
        m = motion[q[1], q[0]]
        land = q + 0.5 + u * m[:2] - centre
        r = np.max(np.abs(land)) if np.all(raw == q) else 1e30
        if r < best[0]:
            best = (r, q, m)
        p = centre - u * m[:2]
        if np.all(np.floor(p).astype(int) == raw):
            break
    return best


SEED_MERGE = 1.0


def front_seeds(vn, tilemax, tile_xy, own, max_seeds: int, max_disp: float) -> list:
    """Distinct neighbourhood seeds: the largest first, then the 3x3 tile maxima in scan
    order (bottom row first), skipping short ones and those within SEED_MERGE px (per axis)
    of the own displacement or of a seed already taken."""
    seeds = []

    def add(v):
        if len(seeds) == max_seeds or np.hypot(*v) <= 1.0:
            return
        if np.all(np.abs(v - own) < SEED_MERGE):
            return
        if any(np.all(np.abs(v - s) < SEED_MERGE) for s in seeds):
            return
        seeds.append(v)

    add(vn)
    th, tw = tilemax.shape[:2]
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            tx, ty = tile_xy[0] + dx, tile_xy[1] + dy
            if 0 <= tx < tw and 0 <= ty < th:
                add(clamp_length(tilemax[ty, tx], max_disp))
    return seeds


def time_composite(front, front_color, back, back_color, tilemax, neighbormax, tile: int,
                   max_disp: float, samples_min=8, samples_max=48, spacing=2.0,
                   tolerance=0.65, iterations=3, max_seeds=3) -> np.ndarray:
    """hybrid_time.frag with jitter 0 (times at stratum centres) and one revealed layer."""
    h, w = front.shape[:2]
    layers = [(front, front_color), (back, back_color)]
    out = np.zeros((h, w, 3))
    for y in range(h):
        for x in range(w):
            centre = np.array([x + 0.5, y + 0.5])
            own = front_color[y, x]
            vn = clamp_length(neighbormax[y // tile, x // tile], max_disp)
            fx, bx = front[y, x], back[y, x]
            reach = max(np.hypot(*vn), np.hypot(*fx[:2]), np.hypot(*bx[:2]))
            if reach <= 1.0:
                out[y, x] = own
                continue
            seeds = [(0, fx[:2])]
            seeds += [(0, v) for v in front_seeds(vn, tilemax, (x // tile, y // tile), fx[:2],
                                                  max_seeds, max_disp)]
            seeds += [(1, bx[:2])]
            n = int(np.clip(int(np.ceil(reach / spacing)), samples_min, samples_max))
            total = np.zeros(3)
            for k in range(n):
                u = (k + 0.5) / n - 0.5
                best_z, best, covered = np.inf, None, False
                miss, miss_behind, stand_in = np.inf, False, own
                for layer, seed in seeds:
                    motion, colour = layers[layer]
                    r, q, m = walk(motion, centre, u, seed, iterations, tolerance)
                    if r >= 1e29:
                        continue
                    if r <= tolerance:
                        if m[2] < best_z:
                            best_z, best, covered = m[2], colour[q[1], q[0]], True
                    elif not covered:
                        behind = m[2] > fx[2]
                        if (behind and not miss_behind) or (behind == miss_behind and r < miss):
                            miss, miss_behind, stand_in = r, behind, colour[q[1], q[0]]
                total += best if covered else stand_in
            out[y, x] = total / n
    return out




def bucket_composite(front, front_color, back, back_color, neighbormax, tile: int,
                     max_disp: float, samples_min=8, samples_max=48, spacing=2.0,
                     merge_cos=MERGE_COS) -> np.ndarray:
    """hybrid_bucket.frag (its full variant) with jitter 0 (taps at the centres of their
    pieces)."""
    h, w = front.shape[:2]
    NEAR, OWN, BETWEEN, BACK = range(4)
    out = np.zeros((h, w, 3))

    def taps_for(half):
        return int(np.clip(int(np.ceil(2.0 * half / spacing)), samples_min, samples_max))

    def line(x, y, d, half, n=None, gap=0.0):
        """(a, b, s, pixel) of each tap of the line through (x, y) along d over [-half,
        half] (n taps, or taps_for(half)), the middle [-gap/2, gap/2] left out (n even:
        n/2 equal pieces on either side of it)."""
        n = taps_for(half) if n is None else n
        direction = d / np.hypot(*d)
        piece = (2.0 * half - gap) / n
        for i in range(n):
            a = -half + piece * i + (gap if gap and i >= n // 2 else 0.0)
            b = a + piece
            s = a + 0.5 * piece
            p = np.floor(np.array([x + 0.5, y + 0.5]) + s * direction).astype(int)
            p = np.clip(p, 0, [w - 1, h - 1])
            yield a, b, s, (p[1], p[0])

    def coverage(a, b, s, length):
        if abs(s) > 0.5 * length + 0.5:
            return 0.0
        if length < 1e-3:
            return 1.0 if a <= 0.0 < b else 0.0
        return max(min(b, 0.5 * length) - max(a, -0.5 * length), 0.0) / length

    for y in range(h):
        for x in range(w):
            own_colour = front_color[y, x]
            fx, bx = front[y, x], back[y, x]
            vn = clamp_length(neighbormax[y // tile, x // tile], max_disp)
            if max(np.hypot(*vn), np.hypot(*fx[:2]), np.hypot(*bx[:2])) <= 1.0:
                out[y, x] = own_colour
                continue
            sums = np.zeros((4, 3))
            weights = np.zeros(4)
            far = []
            revealed = bx[3] > 0.5
            own_id, own_depth = fx[3], fx[2]
            back_depth = bx[2] if revealed else np.inf
            back_id = bx[3] - 1.0 if revealed else -1.0
            ln, lo = np.hypot(*vn), np.hypot(*fx[:2])
            rn, ro = 0.5 * ln, 0.5 * lo
            n_own = taps_for(ro)
            own_walk = ro > 0.5
            # The neighbourhood's line merged with the own line where their directions
            # lie within the merge angle: the own line's taps fill every bucket, and the
            # neighbourhood's line walks only its ends beyond the own line's reach.
            merged = (own_walk and n_own <= 32 and rn > 0.5
                      and abs(float(np.dot(vn, fx[:2]))) >= merge_cos * ln * lo)

            def add(k, c, wt):
                sums[k] += wt * c
                weights[k] += wt

            # The own object's presence along its own line's taps (at most 32): at time
            # u the own fragment over the pixel lies in the piece floor((1/2 - u) n).
            presence = []
            if lo >= 1e-3:
                presence = [front[p][3] == own_id
                            for _, _, _, p in line(x, y, fx[:2], ro, min(n_own, 32))]

            def own_covers(s, length):
                """Does the own object cover the pixel at the time u = -s / length that
                a fragment s along the line, moving `length` px, passes it?"""
                if length < 1e-3 or lo < 1e-3:
                    return True
                u = np.clip(-s / length, -0.5, 0.5)
                return presence[min(int(np.floor((0.5 - u) * len(presence) + 1e-3)),
                                    len(presence) - 1)]

            near_free = 0.0
            if own_walk:
                for a, b, s, p in line(x, y, fx[:2], ro):
                    m, c = front[p], front_color[p]
                    length = np.hypot(*m[:2])
                    wt = coverage(a, b, s, length)
                    if m[3] == own_id:
                        add(OWN, c, wt)
                        continue
                    if m[2] >= own_depth:
                        far.append(c)
                    if not merged:
                        continue
                    if m[2] < own_depth:
                        # A nearer fragment hides the own object at this tap: it passes
                        # the pixel while the own object is away.
                        add(NEAR, c, wt)
                        if length >= 1e-3:
                            near_free += wt
                    elif m[3] != back_id and m[2] < back_depth:
                        add(BETWEEN, c, wt)
            else:
                add(OWN, own_colour, 1.0)
            n = taps_for(rn)
            if merged:
                reach = max(rn, ro) - ro
                ends = max(1, int(np.floor(reach * n / (2.0 * rn) + 0.5))) if reach > 1e-3 else 0
                taps = line(x, y, vn, max(rn, ro), 2 * ends, 2.0 * ro) if ends > 0 else ()
            else:
                taps = line(x, y, vn, rn, n) if rn > 0.5 else ()
            for a, b, s, p in taps:
                m, c = front[p], front_color[p]
                length = np.hypot(*m[:2])
                wt = coverage(a, b, s, length)
                if m[3] == own_id:
                    if merged:
                        add(OWN, c, wt)
                elif m[2] < own_depth:
                    add(NEAR, c, wt)
                    if wt > 0.0 and lo >= 1e-3 and not own_covers(s, length):
                        near_free += wt
                elif m[3] != back_id and m[2] < back_depth:
                    add(BETWEEN, c, wt)
                    far.append(c)
            fill = np.mean(far, axis=0) if far else own_colour
            back_all, back_all_w = np.zeros(3), 0.0
            if revealed:
                fill = back_color[y, x]
                rb = 0.5 * np.hypot(*bx[:2])
                if rb > 0.5:
                    for a, b, s, p in line(x, y, bx[:2], rb):
                        m = back[p]
                        mid = m[3] - 1.0 if m[3] > 0.5 else front[p][3]
                        if mid != back_id and m[2] < back_depth * 0.999:
                            continue
                        length = np.hypot(*m[:2])
                        wt = coverage(a, b, s, length)
                        back_all += wt * back_color[p]
                        back_all_w += wt
                        # Paired with the time u it passes the pixel: not while the own
                        # object covers it (its fragment then at x - u D, frame time).
                        if wt > 0.0 and length >= 1e-3 and own_covers(s, length):
                            wt = 0.0
                        add(BACK, back_color[p], wt)
                else:
                    add(BACK, fill, 1.0)
            if back_all_w > 0.0:
                mean = sums[BACK] / weights[BACK] if weights[BACK] > 0 else back_all / back_all_w
                weights[BACK] = min(1.0, back_all_w)
                sums[BACK] = mean * weights[BACK]
            c = fill
            for k in (BACK, BETWEEN):
                alpha = min(1.0, weights[k])
                mean = sums[k] / weights[k] if weights[k] > 0 else np.zeros(3)
                c = alpha * mean + (1.0 - alpha) * c
            # Nearer fragments over the own object, or beside it while it is away.
            a_n, a_o = min(1.0, weights[NEAR]), min(1.0, weights[OWN])
            vis_own = max(a_o - (a_n - min(near_free, a_n)), 0.0)
            vis_rest = max(1.0 - a_n - vis_own, 0.0)
            near_c = sums[NEAR] / weights[NEAR] if weights[NEAR] > 0 else np.zeros(3)
            own_c = sums[OWN] / weights[OWN] if weights[OWN] > 0 else np.zeros(3)
            out[y, x] = ((a_n * near_c + vis_own * own_c + vis_rest * c)
                         / max(a_n + vis_own + vis_rest, 1e-6))
    return out


def time_average(width: int, n: int, colour_at) -> np.ndarray:
    """Mean over n stratified times u in [-1/2, 1/2] of colour_at(u, x) ((rows, 3): what
    column x shows at time u), for every column x: an analytic scene's exposure."""
    cols = [np.mean([colour_at((k + 0.5) / n - 0.5, x) for k in range(n)], axis=0)
            for x in range(width)]
    return np.stack(cols, axis=1)


def box_shutter_bar(fg, bg, x0: int, x1: int, d: float, n: int) -> np.ndarray:
    """Analytic: one row of a bar covering pixel centres x0..x1-1 at the frame time,
    translating by d px over the exposure over a static background; the mean of n
    stratified time samples of each pixel centre's colour. fg, bg: (W, 3) colours of the
    bar's and the background's frame-time pixels; returns (W, 3)."""
    fg, bg = np.asarray(fg, np.float64), np.asarray(bg, np.float64)
    out = np.zeros(bg.shape)
    for x in range(len(bg)):
        acc = np.zeros(3)
        for k in range(n):
            u = (k + 0.5) / n - 0.5
            src = int(np.floor(x + 0.5 - u * d))    # the bar pixel on x at time u, if any
            acc += fg[src] if x0 <= src < x1 else bg[x]
        out[x] = acc / n
    return out
