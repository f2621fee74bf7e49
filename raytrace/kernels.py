"""Compiled loops (numba) for the reveal's per-ray bookkeeping around Embree's `run`.

The reveal traces ten to a hundred thousand rays a frame. As chains of numpy operations
over those rays (box culling, gathers, transforms, hit merges), each a full pass over
memory and a Python call (~5 us each), the bookkeeping would cost more than Embree's
tracing. Each function here does one such chain in a single loop,
operation for operation in the same precision (float32 where the rays are float32), so
the hits do not change (tests/test_raytrace.py: against tracing without culling, against
the scene without the own object, by hand). The box test alone differs from its numpy
form, where a ray lies exactly in a face plane of the padded box (see box_rows).

Compiled once per machine (cache=True, next to this file or in numba's user cache) and
run without the GIL (nogil=True), so the reveal's worker threads run them side by side.
"""
from __future__ import annotations

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True)


# A direction component of 0 gives an infinite inverse; clamped to this, the slab test
# needs no NaN rule (0 * inf) and its loop vectorises. It may then drop a ray lying
# exactly in a face plane of the box: the caller pads the box, so such a ray cannot hit.
_BIG = np.float32(1e30)


@njit(inline="always")
def _slab(l, h, inv, near, far):
    """[near, far] cut by one axis' slab [l, h] (box bounds less the origin), float32."""
    x = min(max(inv, -_BIG), _BIG)
    a, b = l * x, h * x
    return max(near, min(a, b)), min(far, max(a, b))


@njit(inline="always")
def _meets(l0, l1, l2, h0, h1, h2, ix, iy, iz, start, best):
    near, far = _slab(l0, h0, ix, np.float32(start), np.float32(best))
    near, far = _slab(l1, h1, iy, near, far)
    near, far = _slab(l2, h2, iz, near, far)
    return near <= far


@njit(**_JIT)
def box_rows(o, inv_d, shared, lo, hi, start, best, excl, skip_id, first, end):
    """Rows first..end-1 of the rays o + s d that meet the box [lo, hi] for some s in
    [start, best] and are not excluded (excl != skip_id): the slab test in float32.
    inv_d: (3, n), the inverse directions component by component (contiguous rows: the
    loop vectorises, ~5x faster than over (n, 3) rows). shared: every ray starts at o[0]."""
    n = max(end - first, 0)
    ix, iy, iz = inv_d[0, first:end], inv_d[1, first:end], inv_d[2, first:end]
    start, best, excl = start[first:end], best[first:end], excl[first:end]
    meets = np.empty(n, np.bool_)
    if shared:
        l0, l1, l2 = (np.float32(lo[0]) - o[0, 0], np.float32(lo[1]) - o[0, 1],
                      np.float32(lo[2]) - o[0, 2])
        h0, h1, h2 = (np.float32(hi[0]) - o[0, 0], np.float32(hi[1]) - o[0, 1],
                      np.float32(hi[2]) - o[0, 2])
        for i in range(n):
            meets[i] = (_meets(l0, l1, l2, h0, h1, h2, ix[i], iy[i], iz[i], start[i], best[i])
                        & (excl[i] != skip_id))
    else:
        o = o[first:end]
        for i in range(n):
            l0, l1, l2 = (np.float32(lo[0]) - o[i, 0], np.float32(lo[1]) - o[i, 1],
                          np.float32(lo[2]) - o[i, 2])
            h0, h1, h2 = (np.float32(hi[0]) - o[i, 0], np.float32(hi[1]) - o[i, 1],
                          np.float32(hi[2]) - o[i, 2])
            meets[i] = (_meets(l0, l1, l2, h0, h1, h2, ix[i], iy[i], iz[i], start[i], best[i])
                        & (excl[i] != skip_id))
    return first + np.flatnonzero(meets)


@njit(**_JIT)
def boxes_rows(o, inv_d, shared, lo, hi, start, best, excl, ids, spans):
    """box_rows for m boxes at once (lo, hi (m, 3), ids (m,) the objects skipped, spans
    (m, 2) the rows each tests): (rows, cuts), box b's rows rows[cuts[b]:cuts[b + 1]]."""
    m = lo.shape[0]
    total = 0
    for b in range(m):
        total += max(spans[b, 1] - spans[b, 0], 0)
    rows = np.empty(total, np.int64)
    cuts = np.zeros(m + 1, np.int64)
    k = 0
    for b in range(m):
        r = box_rows(o, inv_d, shared, lo[b], hi[b], start, best, excl, ids[b],
                     spans[b, 0], spans[b, 1])
        rows[k:k + r.shape[0]] = r
        k += r.shape[0]
        cuts[b + 1] = k
    return rows[:k], cuts


@njit(**_JIT)
def ray_arrays(o, d, start, shared):
    """The rays moved to their starts (o + start d, in float64) as Embree takes them
    (float32 origins and directions), and the directions' float32 inverses (inf for a
    zero component) as box_rows takes them, (3, n). shared: every origin is o[0]."""
    n = d.shape[0]
    o32 = np.empty((n, 3), np.float32)
    d32 = np.empty((n, 3), np.float32)
    inv_d = np.empty((3, n), np.float32)
    one = np.float32(1.0)
    for i in range(n):
        r = 0 if shared else i
        s = start[i]
        for c in range(3):
            o32[i, c] = np.float32(o[r, c] + d[i, c] * s)
            f = np.float32(d[i, c])
            d32[i, c] = f
            inv_d[c, i] = one / f if f != 0 else (np.inf if not np.signbit(f) else -np.inf)
    return o32, d32, inv_d


@njit(inline="always")
def _xform(m, x, y, z, w):
    # transform_points' float32 order: ((m0 x + m1 y) + m2 z) + w m3, row by row.
    return (m[0] * x + m[1] * y + m[2] * z + w * m[3])


@njit(**_JIT)
def local_rays(o, d, rows, shared, inv, rotate, start, best):
    """The rays `rows` carried into an object's space by `inv` (float32 4x4, column
    vectors; directions not renormalised, and left as they are when not `rotate`), and
    their Embree far limits float32(best - start)."""
    m = rows.shape[0]
    lo = np.empty((m, 3), np.float32)
    ld = np.empty((m, 3), np.float32)
    tfar = np.empty(m, np.float32)
    one, zero = np.float32(1.0), np.float32(0.0)
    for k in range(m):
        i = rows[k]
        r = 0 if shared else i
        if k == 0 or not shared:
            ox, oy, oz = o[r, 0], o[r, 1], o[r, 2]
            px = _xform(inv[0], ox, oy, oz, one)
            py = _xform(inv[1], ox, oy, oz, one)
            pz = _xform(inv[2], ox, oy, oz, one)
        lo[k, 0], lo[k, 1], lo[k, 2] = px, py, pz
        dx, dy, dz = d[i, 0], d[i, 1], d[i, 2]
        if rotate:
            ld[k, 0] = _xform(inv[0], dx, dy, dz, zero)
            ld[k, 1] = _xform(inv[1], dx, dy, dz, zero)
            ld[k, 2] = _xform(inv[2], dx, dy, dz, zero)
        else:
            ld[k, 0], ld[k, 1], ld[k, 2] = dx, dy, dz
        tfar[k] = np.float32(best[i] - start[i])
    return lo, ld, tfar


@njit(**_JIT)
def merge_hits(rows, geom, prim, hu, hv, htfar, start, best, object_id, prim_id, u, v,
               ids, single_id):
    """Take the hits of rays `rows` (Embree's output for them) that lie nearer than the
    best so far, in place. The object hit is single_id where it is >= 0, else
    ids[geomID + 1]. Returns how many were taken."""
    taken = 0
    for k in range(rows.shape[0]):
        g = geom[k]
        if g < 0:
            continue
        i = rows[k]
        dist = start[i] + htfar[k]
        if dist < best[i]:
            object_id[i] = single_id if single_id >= 0 else ids[g + 1]
            prim_id[i] = prim[k]
            u[i] = hu[k]
            v[i] = hv[k]
            best[i] = dist
            taken += 1
    return taken


@njit(**_JIT)
def member(values, table):
    """table[values] where a value is inside the table, else False: np.isin for small
    non-negative ids with a boolean table over them."""
    n = values.shape[0]
    out = np.zeros(n, np.bool_)
    for i in range(n):
        x = values[i]
        if x < table.shape[0]:
            out[i] = table[x]
    return out


@njit(inline="always")
def _take_view_hit(i, key, v_id, v_prim, v_u, v_v, v_dist, best, object_id, prim_id, u, v,
                   from_view):
    """Ray i takes the view's kept static hit of pixel `key` where there is one nearer
    than its best so far; from_view marks it."""
    if v_id[key] != 0 and v_dist[key] < best[i]:
        object_id[i] = v_id[key]
        prim_id[i] = v_prim[key]
        u[i] = v_u[key]
        v[i] = v_v[key]
        best[i] = v_dist[key]
        from_view[i] = True


@njit(**_JIT)
def view_lookup(left, static_own, pixels, known, v_id, v_prim, v_u, v_v, v_dist, best,
                object_id, prim_id, u, v, from_view):
    """Of the rays `left`, those without a static own object take the view's kept static
    hit of their pixel where it is known and nearer than the best so far, in place (as
    view_store); returned: the rays whose pixel's hit is not known yet and those pixels,
    and the rays with a static own object. One pass: a still camera's frames know them
    all."""
    n = left.shape[0]
    new_rows = np.empty(n, np.int64)
    new_keys = np.empty(n, np.int64)
    rest = np.empty(n, np.int64)
    b = c = 0
    for k in range(n):
        i = left[k]
        if static_own[i]:
            rest[c] = i
            c += 1
            continue
        key = pixels[i]
        if not known[key]:
            new_rows[b] = i
            new_keys[b] = key
            b += 1
        else:
            _take_view_hit(i, key, v_id, v_prim, v_u, v_v, v_dist, best, object_id, prim_id,
                           u, v, from_view)
    return new_rows[:b], new_keys[:b], rest[:c]


@njit(**_JIT)
def view_store(rows, keys, geom, prim, hu, hv, htfar, start, id_of, known, v_id, v_prim, v_u,
               v_v, v_dist, best, object_id, prim_id, u, v, from_view):
    """The static scene's hits of rays `rows` (Embree's output for them, traced from their
    starts) kept as the view's hits of pixels `keys` (object id_of[geomID + 1], distance
    start + tfar), then taken by each ray where nearer than its best so far, in place;
    from_view marks the rays that took one. (One pass, not ten numpy calls.)"""
    for k in range(rows.shape[0]):
        i, key = rows[k], keys[k]
        v_id[key] = id_of[geom[k] + 1]
        v_prim[key] = prim[k]
        v_u[key] = hu[k]
        v_v[key] = hv[k]
        v_dist[key] = start[i] + htfar[k]
        known[key] = True
        _take_view_hit(i, key, v_id, v_prim, v_u, v_v, v_dist, best, object_id, prim_id, u, v,
                       from_view)


@njit(**_JIT)
def layer_columns(object_id, distance, u, v, origin, direction, cos, background_depth):
    """A revealed layer's view depth (distance * cos where hit, else background_depth),
    world position (origin + distance * direction where hit, else 0) and (u, v)."""
    n = object_id.shape[0]
    depth = np.empty(n)
    world = np.zeros((n, 3))
    bary = np.empty((n, 2), np.float32)
    for i in range(n):
        bary[i, 0], bary[i, 1] = u[i], v[i]
        if object_id[i] != 0:
            t = distance[i]
            depth[i] = t * cos[i]
            for c in range(3):
                world[i, c] = origin[i, c] + direction[i, c] * t
        else:
            depth[i] = background_depth
    return depth, world, bary


@njit(**_JIT)
def view_clip(direction, fwd, near, far):
    """Per unit ray from the eye: cos(ray, forward) (view depth = distance * cos) and the
    distances along it of the near and far planes, near / cos and far / cos."""
    n = direction.shape[0]
    cos = np.empty(n)
    t0 = np.empty(n)
    t1 = np.empty(n)
    for i in range(n):
        c = direction[i, 0] * fwd[0] + direction[i, 1] * fwd[1] + direction[i, 2] * fwd[2]
        cos[i] = c
        t0[i] = near / c
        t1[i] = far / c
    return cos, t0, t1


@njit(**_JIT)
def row_keys(d, fwd, up, rounding):
    """embree_scene.RowIndex's key of rays d (n, 3) from one eye: the running maximum of
    -(d . up) / (d . forward), up negated where the key runs down the rays (rows bottom to
    top); (key, sign of up), sign 0 where there is no index: a ray not in front of the
    eye, or rays not in row order (a key below the one before by more than rounding)."""
    n = d.shape[0]
    key = np.empty(n, np.float64)
    for i in range(n):
        along = d[i, 0] * fwd[0] + d[i, 1] * fwd[1] + d[i, 2] * fwd[2]
        if not along > 0.0:
            return key[:0], 0.0
        key[i] = -(d[i, 0] * up[0] + d[i, 1] * up[1] + d[i, 2] * up[2]) / along
    sign = 1.0
    if n and key[0] > key[n - 1]:
        sign = -1.0
    for i in range(n):
        key[i] *= sign
    previous = key[0] if n else 0.0
    for i in range(1, n):
        raw = key[i]
        if not raw >= previous - rounding:
            return key[:0], 0.0
        previous = raw
        key[i] = max(raw, key[i - 1])
    return key, sign


@njit(inline="always")
def _bisect(a, x, right):
    """np.searchsorted(a, x, "right" if right else "left") on ascending a."""
    lo, hi = 0, a.shape[0]
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < x or (right and a[mid] == x):
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(**_JIT)
def row_spans(key, eye, fwd, up, lo, hi, rel_pad):
    """(m, 2) [first, end) spans of the rays (by RowIndex key, ascending) that can meet
    each box [lo[b], hi[b]]: the keys of its corners (extremes of the key over a box wholly
    in front of the eye), widened by rel_pad (1 + the largest |corner key|) for the rays'
    float rounding; every ray for a box not wholly in front."""
    m = lo.shape[0]
    out = np.empty((m, 2), np.int64)
    for b in range(m):
        k_min, k_max, k_abs = np.inf, -np.inf, 0.0
        front = True
        for c in range(8):
            x = (hi[b, 0] if c & 1 else lo[b, 0]) - eye[0]
            y = (hi[b, 1] if c & 2 else lo[b, 1]) - eye[1]
            z = (hi[b, 2] if c & 4 else lo[b, 2]) - eye[2]
            along = x * fwd[0] + y * fwd[1] + z * fwd[2]
            if not along > 0.0:
                front = False
                break
            k = -(x * up[0] + y * up[1] + z * up[2]) / along
            k_min, k_max, k_abs = min(k_min, k), max(k_max, k), max(k_abs, abs(k))
        if not front:
            out[b, 0], out[b, 1] = 0, key.shape[0]
            continue
        pad = rel_pad * (1.0 + k_abs)
        out[b, 0] = _bisect(key, k_min - pad, False)
        out[b, 1] = _bisect(key, k_max + pad, True)
    return out


@njit(**_JIT)
def group_rows(values, member):
    """The rows i with member[i], grouped by values[i] (ascending), in row order within a
    group (a counting sort: the values are small ids), and where each group starts
    (with the end appended): np.argsort(values[rows], kind="stable") and its cuts."""
    n = values.shape[0]
    top = 0
    for i in range(n):
        if member[i]:
            top = max(top, values[i])
    count = np.zeros(top + 2, np.int64)
    for i in range(n):
        if member[i]:
            count[values[i] + 1] += 1
    groups = 0
    for v in range(top + 1):
        if count[v + 1] > 0:
            groups += 1
    for v in range(top + 1):
        count[v + 1] += count[v]
    order = np.empty(count[top + 1], np.int64)
    fill = count[:top + 1].copy()
    for i in range(n):
        if member[i]:
            order[fill[values[i]]] = i
            fill[values[i]] += 1
    starts = np.empty(groups + 1, np.int64)
    g = 0
    for v in range(top + 1):
        if count[v + 1] > count[v]:
            starts[g] = count[v]
            g += 1
    starts[groups] = order.shape[0]
    return order, starts


@njit(**_JIT)
def gather_rays(o32, d32, start, best, rows):
    """Rays `rows` as Embree takes them: origins, directions, far limits best - start."""
    m = rows.shape[0]
    o = np.empty((m, 3), np.float32)
    d = np.empty((m, 3), np.float32)
    tfar = np.empty(m, np.float32)
    for k in range(m):
        i = rows[k]
        for c in range(3):
            o[k, c] = o32[i, c]
            d[k, c] = d32[i, c]
        tfar[k] = np.float32(best[i] - start[i])
    return o, d, tfar


@njit(**_JIT)
def world_boxes(ms, corners, rel_pad, abs_pad):
    """The axis-aligned world boxes of corners[k] (8, 3) carried by the 4x4 ms[k] (column
    vectors, transform_points' order of operations), each padded by rel_pad times its
    largest side plus abs_pad: (lo, hi), (m, 3) each."""
    m = ms.shape[0]
    lo = np.full((m, 3), np.inf)
    hi = np.full((m, 3), -np.inf)
    for b in range(m):
        for k in range(corners.shape[1]):
            x, y, z = corners[b, k, 0], corners[b, k, 1], corners[b, k, 2]
            for i in range(3):
                v = ms[b, i, 0] * x + ms[b, i, 1] * y + ms[b, i, 2] * z + 1.0 * ms[b, i, 3]
                lo[b, i] = min(lo[b, i], v)
                hi[b, i] = max(hi[b, i], v)
        pad = rel_pad * max(hi[b, 0] - lo[b, 0], hi[b, 1] - lo[b, 1],
                            hi[b, 2] - lo[b, 2]) + abs_pad
        for i in range(3):
            lo[b, i] -= pad
            hi[b, i] += pad
    return lo, hi


@njit(**_JIT)
def affine_inverses(ms):
    """(inverses, ok): the inverse of each affine 4x4 of ms (m, 4, 4) (last row 0, 0, 0,
    1), as float32: the 3x3's adjugate over its determinant, then -A^-1 t. ok is False
    where a determinant is zero, subnormal or not finite (the caller takes
    np.linalg.inv). np.linalg.inv costs ~10 us a call here, ~40-80 in the frame."""
    m = ms.shape[0]
    out = np.zeros((m, 4, 4), np.float32)
    inv = np.empty((3, 3))
    for b in range(m):
        a = ms[b]
        det = (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
               + a[0, 1] * (a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2])
               + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]))
        if not (abs(det) >= 1e-300 and abs(det) < np.inf):
            return out, False
        for i in range(3):
            for j in range(3):
                # cofactor C[j, i] (the adjugate's entry i, j), cyclic indices
                r0, r1 = (j + 1) % 3, (j + 2) % 3
                c0, c1 = (i + 1) % 3, (i + 2) % 3
                inv[i, j] = (a[r0, c0] * a[r1, c1] - a[r0, c1] * a[r1, c0]) / det
        for i in range(3):
            for j in range(3):
                out[b, i, j] = inv[i, j]
            out[b, i, 3] = -(inv[i, 0] * a[0, 3] + inv[i, 1] * a[1, 3] + inv[i, 2] * a[2, 3])
        out[b, 3, 3] = 1.0
    return out, True


@njit(**_JIT)
def turns_or_scales(invs):
    """Per 4x4 of invs (m, 4, 4): whether its upper 3x3 is not exactly the identity."""
    out = np.zeros(invs.shape[0], np.bool_)
    for b in range(invs.shape[0]):
        for i in range(3):
            for j in range(3):
                if invs[b, i, j] != (1.0 if i == j else 0.0):
                    out[b] = True
    return out
