#version 330 core
// The hybrid mode's bucketed composite (docs/algorithms.md 4.3), a gather: fragments found along
// sampling lines through the pixel are sorted into buckets, each weighted by the exact
// share of the exposure during which its piece of surface covers the pixel, and the
// buckets are combined front to back with "over":
//   0 nearer other objects, 1 the pixel's own object, 2 other objects between it and the
//   revealed surface, 3 the revealed surface (and what lies behind it).
// A line of n taps through the pixel, of half-length R, is cut into n equal pieces; tap i
// stands for the piece [a, b] of signed distances from the pixel and fetches its fragment
// at a jittered point inside it. A fragment moving |D| px over the exposure covers the
// pixel while the pixel lies within its box-shaped spread: a fraction
// overlap([a, b], [-|D|/2, |D|/2]) / |D| of the exposure. So a surface filling the line
// sums to exactly 1 whatever the jitter. Lines, in the order they run:
//   the own line, along the pixel's own displacement: its own object's coverage and
//     colour; its taps also record where the own object lies along its path, for the
//     time pairing of the lines after it;
//   the neighbourhood's line, along the largest displacement around (NeighborMax): what
//     passes over the pixel. Where that displacement lies within MERGE_COS of the own
//     one (a camera pan: every surface moves about the same way), the lines are merged:
//     the own line's taps fill the neighbourhood's buckets too, and the neighbourhood's
//     line walks only its two ends beyond the own line's reach, where the own object may
//     still reach the pixel if it moves faster there (one line's taps instead of two);
//   the revealed layer's line, along its own displacement (the background blurred along
//     its own motion).
// A bucket's coverage is min(1, sum of weights); the revealed colour fills what the
// background bucket leaves (centre fill); fragments of the revealed object seen beside the
// pixel's own object belong to the revealed layer's line only. Without a revealed
// background, the farther fragments' plain mean fills instead (the mirrored background of
// post-process filters).
// BACK_LAYER 0 compiles the variant for tiles without a revealed pixel (the revealed
// layer's line never runs there), OWN_STILL 1 the one for tiles where no pixel moves
// (|D| < 1e-3: no own line, no time pairing): llvmpipe would still pay for them (a branch
// in a loop costs even where no pixel takes it; both sides run where an 8-wide group
// disagrees). SIMPLE 1 compiles the one for tiles with no other object within the lines'
// reach (viewer/render/modes/hybrid/composite.py near_outlines, which also covers the merged
// own lines' spread off the neighbourhood's direction): every tap lands on the own object,
// so the buckets of other objects stay empty and the unmerged neighbourhood's line adds
// nothing. All four give the image the full variant gives.
// With a path (SEGMENTS > 1, glsl/passes/path.glsl) the own and the neighbourhood's lines walk
// paths instead: what covers the pixel during segment k (a share 1/K of the exposure) is
// what lies along that segment reversed, centred at x minus the segment's midpoint offset
// (the pixel's own path for the own line, the NeighborMax tile's for the neighbourhood's),
// each tap weighted by its fragment's own segment-k length and 1/K; the own line's taps,
// in time order, give the presence bits; the lines are never merged.
#include "graph/noise.glsl"
#include "modes/hybrid/hybrid_layers.glsl"
uniform sampler2D u_neighbormax;
#if SEGMENTS > 1
#define PATH_READ
#include "passes/path.glsl"
uniform sampler2D u_neighbormax_path0;
#if SEGMENTS == 4
uniform sampler2D u_neighbormax_path1;
#endif
#endif
uniform int u_tile;
uniform int u_samples_min;
uniform int u_samples_max;
uniform float u_spacing;
uniform float u_jitter;
out vec4 out_color;

const int NEAR = 0, OWN = 1, BETWEEN = 2, BACK = 3;
vec3 g_sum[4];
float g_weight[4];
float g_near_free;        // NEAR weight at times the own object is away from the pixel
vec3 g_far_sum;           // unweighted farther fragments: the fill without a reveal
float g_far_count;

ivec2 g_size;
float g_jitter;

vec2 clamp_length(vec2 d) {
    float l = length(d);
    return l > u_max_disp ? d * (u_max_disp / l) : d;
}

// The share of the exposure during which a surface piece at signed distances [a, b] from
// the pixel, moving `len` px, covers it; a still piece covers it iff it contains it. The
// fragment fetched for the piece, at distance s, must itself reach the pixel (to within
// half a pixel): a slow fragment stands only for itself, not for a longer piece.
float g_s;
float coverage(float a, float b, float len) {
    if (abs(g_s) > 0.5 * len + 0.5) return 0.0;
    if (len < 1e-3) return (a <= 0.0 && 0.0 < b) ? 1.0 : 0.0;
    return max(min(b, 0.5 * len) - max(a, -0.5 * len), 0.0) / len;
}

// Does the own object cover pixel x at the time the tap's fragment (at signed distance
// g_s along the line, moving len px) passes it, u = -g_s / len? Its own fragment then is
// the frame-time one at x - u D_own. A (nearly) still own surface covers at every time.
// Answered from the own object's presence along its path, sampled once per pixel: bit i
// of g_own_bits says whether tap i of n on the own line (the own displacement's line, at
// its jittered point in piece i) landed on the own object, and the own fragment at time u
// lies in piece floor((1/2 - u) n). The bits come from the own line where it runs, from a
// presence walk (one fetch a tap) otherwise. A fetch here instead would run for every tap
// of the neighbourhood's and the revealed layer's lines in every pixel: llvmpipe runs a
// branch in a loop whether taken or not.
const int BITS = 32;
uint g_own_bits;
int g_bits_n;
void presence_reset(int n) { g_own_bits = 0u; g_bits_n = n; }
void presence_add(int i, bool own) { g_own_bits |= own ? (1u << uint(i)) : 0u; }
// (u: the time in [-1/2, 1/2] of the exposure; bit 0 the latest piece)
bool own_covers_at(float u) {
    // (+1e-3: uniform motion puts u on piece boundaries exactly; rounding then decides,
    // so ties are moved off them, for every float precision alike)
    int i = min(int(floor((0.5 - u) * float(g_bits_n) + 1e-3)), g_bits_n - 1);
    return ((g_own_bits >> uint(i)) & 1u) != 0u;
}
bool own_covers(float len, float lo) {
    if (len < 1e-3 || lo < 1e-3) return true;
    return own_covers_at(clamp(-g_s / len, -0.5, 0.5));
}

int taps_for(float half_len) {
    return clamp(int(ceil(2.0 * half_len / u_spacing)), u_samples_min, u_samples_max);
}

// Tap i of n on the line x + s dir, s in [-R, R]: its piece [a, b], its jittered point
// s (in g_s) and the pixel there.
ivec2 tap(ivec2 x, vec2 dir, float R, int i, int n, out float a, out float b) {
    float h = R / float(n);
    a = -R + 2.0 * h * float(i);
    b = a + 2.0 * h;
    g_s = a + 2.0 * h * g_jitter;
    return clamp(ivec2(floor(vec2(x) + 0.5 + g_s * dir)), ivec2(0), g_size - 1);
}

// Tap i of n on the line x + s dir with the middle [-gap/2, gap/2] left out: pieces of
// equal length (2R - gap) / n, the first m before the gap, the rest after it.
ivec2 tap_gap(ivec2 x, vec2 dir, float R, float gap, int i, int n, int m,
              out float a, out float b) {
    float h = (2.0 * R - gap) / float(n);
    a = -R + h * float(i) + (i >= m ? gap : 0.0);
    b = a + h;
    g_s = a + h * g_jitter;
    return clamp(ivec2(floor(vec2(x) + 0.5 + g_s * dir)), ivec2(0), g_size - 1);
}

#if SEGMENTS > 1
// Taps per segment of a path: as a line as long as its longest segment gets, a share
// 1/K of the tap counts, and at most BITS in all (one presence bit a tap).
int path_taps(vec2 o[PATH_POINTS]) {
    float longest = 0.0;
    for (int k = 0; k < SEGMENTS; ++k) longest = max(longest, length(o[k + 1] - o[k]));
    int lo = max(1, (u_samples_min + SEGMENTS - 1) / SEGMENTS);
    int hi = max(lo, u_samples_max / SEGMENTS);
    return min(clamp(int(ceil(longest / u_spacing)), lo, hi), BITS / SEGMENTS);
}

// Segment k of a path as a sampling line: its midpoint offset, unit direction, half length.
float segment_line(vec2 o[PATH_POINTS], int k, out vec2 mid, out vec2 dir) {
    vec2 d = o[k + 1] - o[k];
    float l = length(d);
    mid = 0.5 * (o[k] + o[k + 1]);
    dir = l > 1e-6 ? d / l : vec2(1.0, 0.0);
    return 0.5 * l;
}

// The neighbourhood's line for segment k: from x out to the segment's farther point
// (px offsets; its midpoint, unit direction and half length). A surface moving like the
// NeighborMax tile's but slower passes x during segment k nearer x than the tile's own
// segment: on the segment scaled towards the frame-time point, which the spoke covers.
float spoke_line(vec2 o[PATH_POINTS], int k, out vec2 mid, out vec2 dir) {
    vec2 far = dot(o[k], o[k]) > dot(o[k + 1], o[k + 1]) ? o[k] : o[k + 1];
    float l = length(far);
    mid = 0.5 * far;
    dir = l > 1e-6 ? far / l : vec2(1.0, 0.0);
    return 0.5 * l;
}

// Taps per spoke: as path_taps, by the longest spoke, twice the share (spokes overlap).
int spoke_taps(vec2 o[PATH_POINTS]) {
    float longest = 0.0;
    for (int k = 0; k < PATH_POINTS; ++k) longest = max(longest, length(o[k]));
    int lo = max(1, (u_samples_min + SEGMENTS - 1) / SEGMENTS);
    int hi = max(lo, 2 * u_samples_max / SEGMENTS);
    return clamp(int(ceil(longest / u_spacing)), lo, hi);
}

// Tap i of n on the line c + s dir, s in [-R, R] (tap()'s pieces and jitter), c in px.
ivec2 tap_at(vec2 c, vec2 dir, float R, int i, int n, out float a, out float b) {
    float h = R / float(n);
    a = -R + 2.0 * h * float(i);
    b = a + 2.0 * h;
    g_s = a + 2.0 * h * g_jitter;
    return clamp(ivec2(floor(c + g_s * dir)), ivec2(0), g_size - 1);
}

// The share of the exposure during which the fragment at tap y (piece [a, b], at g_s, of
// the line along segment k centred at x - mid) covers the pixel in segment k, from its
// own path: measured along its own segment k (its direction; the line's where it is
// still), x lies g_s' from that segment's midpoint, and the piece moves by g_s' - g_s
// (what lies beside x is not tested: as on a straight line, a surface filling the line
// then sums to 1). 1/K of coverage(); g_s becomes g_s', len the segment's length.
float path_coverage(ivec2 y, int k, vec2 mid, vec2 dir, float a, float b, out float len) {
    vec2 oy[PATH_POINTS];
    front_path_raw(y, oy);
    clamp_path(oy, u_max_disp);
    vec2 d = oy[k + 1] - oy[k];
    len = length(d);
    vec2 dy = len >= 1e-3 ? d / len : dir;
    // x minus the fragment's segment midpoint (the tap's point is x - mid + g_s dir)
    vec2 e = mid - g_s * dir - 0.5 * (oy[k] + oy[k + 1]);
    float s = -dot(e, dy);
    float shift = s - g_s;
    g_s = s;
    return coverage(a + shift, b + shift, len) / float(SEGMENTS);
}
#endif

void add(int bucket, vec3 c, float w) {
    g_sum[bucket] += w * c;
    g_weight[bucket] += w;
}

vec3 over(int bucket, vec3 behind) {
    float alpha = min(1.0, g_weight[bucket]);
    vec3 c = g_weight[bucket] > 0.0 ? g_sum[bucket] / g_weight[bucket] : vec3(0.0);
    return alpha * c + (1.0 - alpha) * behind;
}

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    g_size = textureSize(u_front, 0);
    vec3 own_colour = texelFetch(u_front_color, x, 0).rgb;
    vec4 fx = front_motion(x);
#if BACK_LAYER
    vec4 bx = back_motion(x);
#else
    vec4 bx = vec4(fx.xyz, 0.0);        // nothing revealed in this tile
#endif
    vec2 vn = clamp_length(texelFetch(u_neighbormax, x / u_tile, 0).xy);
#if SEGMENTS > 1
    vec2 po[PATH_POINTS], pn[PATH_POINTS];
    front_path_raw(x, po);
    clamp_path(po, u_max_disp);
#if SEGMENTS == 2
    read_path(u_neighbormax_path0, x / u_tile, pn);
#else
    read_path(u_neighbormax_path0, u_neighbormax_path1, x / u_tile, pn);
#endif
    clamp_path(pn, u_max_disp);
    float reach = max(path_extent(pn), max(path_extent(po), length(bx.xy)));
#else
    float reach = max(length(vn), max(length(fx.xy), length(bx.xy)));
#endif
    if (reach <= 1.0) {
        out_color = vec4(own_colour, 1.0);
        return;
    }
    // Interleaved gradient noise (Jimenez 2014), not white noise: its error is spread at
    // high spatial frequencies, which the eye (and FLIP) weigh least; PSNR / SSIM alike.
    g_jitter = mix(0.5, ign(vec2(x), float(JITTER_STREAM)), u_jitter);
    for (int k = 0; k < 4; ++k) { g_sum[k] = vec3(0.0); g_weight[k] = 0.0; }
    g_far_sum = vec3(0.0);
    g_far_count = 0.0;
    g_near_free = 0.0;
    bool revealed = bx.w > 0.5;
    float own_id = fx.w, own_depth = fx.z;
    // A (nearly) still own surface covers the pixel at every time: no pairing to do.
#if OWN_STILL
    const bool own_moves = false;
#else
#if SEGMENTS > 1
    bool own_moves = path_extent(po) >= 1e-3;
#else
    bool own_moves = dot(fx.xy, fx.xy) >= 1e-6;
#endif
#endif
    float back_depth = revealed ? bx.z : 3.0e38;
    float back_id = revealed ? bx.w - 1.0 : -1.0;
#if SEGMENTS > 1
    float ln = length(vn), lo = path_extent(po);
#else
    float ln = length(vn), lo = length(fx.xy);
#endif
    float ro = 0.5 * lo, rn = 0.5 * ln;
    float a, b;
    presence_reset(1);

#if SEGMENTS > 1
    // The own line along the own path, segment by segment (see the top); its taps in
    // time order (bit 0 the latest) give the presence bits.
#if OWN_STILL
    const bool merged = false;
#else
    const bool merged = false;
    if (own_moves) {
        // What lies on x at time t_k is the surface point that moves there, from x minus
        // its own offset o_k: refined once from the pixel at x - o_k where that is the own
        // object (to second order the pre-image of a rotation; x - o_k alone bends the
        // wrong way).
        vec2 pb[PATH_POINTS];
        for (int k = 0; k < PATH_POINTS; ++k) {
            pb[k] = po[k];
            ivec2 y0 = clamp(ivec2(floor(vec2(x) + 0.5 - po[k])), ivec2(0), g_size - 1);
            if (k != SEGMENTS / 2 && texelFetch(u_front, y0, 0).w == own_id) {
                vec2 oy[PATH_POINTS];
                front_path_raw(y0, oy);
                clamp_path(oy, u_max_disp);
                pb[k] = oy[k];
            }
        }
        int n = path_taps(pb);
        presence_reset(n * SEGMENTS);
        for (int k = 0; k < SEGMENTS; ++k) {
            vec2 mid, dir;
            float r = segment_line(pb, k, mid, dir);
            for (int i = 0; i < n; ++i) {
                ivec2 y = tap_at(vec2(x) + 0.5 - mid, dir, r, i, n, a, b);
                vec4 m = texelFetch(u_front, y, 0);
                vec3 c = texelFetch(u_front_color, y, 0).rgb;
                bool own = m.w == own_id;
                presence_add((SEGMENTS - 1 - k) * n + i, own);
                float len;
                float w = path_coverage(y, k, mid, dir, a, b, len);
                add(OWN, c, own ? w : 0.0);
                bool far = !own && m.z >= own_depth;
                g_far_sum += far ? c : vec3(0.0);
                g_far_count += far ? 1.0 : 0.0;
            }
        }
    } else
#endif
    {
        add(OWN, own_colour, 1.0);            // the own object (nearly) still
    }
#else
    // The own line: the own object's coverage and colour along its displacement, and
    // the bits of its presence along its path for the time pairing.
#if OWN_STILL
    const bool own_walk = false, merged = false;
#else
    int n_own = taps_for(ro);
    bool own_walk = ro > 0.5;
    // Merged lines (see the top): the others passing over are sampled along the own
    // direction within the own line's reach.
    bool merged = own_walk && n_own <= BITS && rn > 0.5
                  && abs(dot(vn, fx.xy)) >= MERGE_COS * ln * lo;
    if (own_moves && (!own_walk || n_own > BITS)) {
        // The own object's presence along its path without its line (or past BITS taps).
        vec2 dir = fx.xy / lo;
        int n = min(n_own, BITS);
        presence_reset(n);
        for (int i = 0; i < n; ++i) {
            ivec2 y = tap(x, dir, ro, i, n, a, b);
            presence_add(i, texelFetch(u_front, y, 0).w == own_id);
        }
    }
    if (own_walk) {
        vec2 dir = fx.xy / lo;
        int n = n_own;
        if (n <= BITS) presence_reset(n);
        for (int i = 0; i < n; ++i) {
            ivec2 y = tap(x, dir, ro, i, n, a, b);
            vec4 m = texelFetch(u_front, y, 0);
            vec3 c = texelFetch(u_front_color, y, 0).rgb;
            bool own = m.w == own_id;
            presence_add(min(i, BITS - 1), own && n <= BITS);
            float len = min(length(m.xy), u_max_disp);
            float w = coverage(a, b, len);
            add(OWN, c, own ? w : 0.0);
            bool far = !own && m.z >= own_depth;
            g_far_sum += far ? c : vec3(0.0);
            g_far_count += far ? 1.0 : 0.0;
#if !SIMPLE
            // A nearer fragment here hides the own object at this tap: it counts as
            // passing the pixel while the own object is away (its exact time pairing
            // would need bits this loop has not set yet; measured as good or better).
            bool near = merged && !own && !far;
            add(NEAR, c, near ? w : 0.0);
            g_near_free += near && len >= 1e-3 ? w : 0.0;
            add(BETWEEN, c, merged && far && m.w != back_id && m.z < back_depth ? w : 0.0);
#endif
        }
    } else
#endif
    {
        add(OWN, own_colour, 1.0);            // the own object (nearly) still
    }
#endif
#if SEGMENTS > 1
    // The neighbourhood's line along the NeighborMax tile's path, segment by segment (each
// on its spoke from x).
#if !SIMPLE
    if (path_extent(pn) > 1.0) {
        int n = spoke_taps(pn);
        for (int k = 0; k < SEGMENTS; ++k) {
            vec2 mid, dir;
            float r = spoke_line(pn, k, mid, dir);
            for (int i = 0; i < n; ++i) {
                ivec2 y = tap_at(vec2(x) + 0.5 - mid, dir, r, i, n, a, b);
                vec4 m = texelFetch(u_front, y, 0);
                vec3 c = texelFetch(u_front_color, y, 0).rgb;
                float len;
                float w = path_coverage(y, k, mid, dir, a, b, len);
                bool own = m.w == own_id;
                bool near = !own && m.z < own_depth;
                bool between = !own && !near && m.w != back_id && m.z < back_depth;
                add(NEAR, c, near ? w : 0.0);
                // The time the fragment passes the pixel: within segment k, at -s / len.
                float u = (float(k) + 0.5 + clamp(-g_s / max(len, 1e-6), -0.5, 0.5))
                          / float(SEGMENTS) - 0.5;
                bool covers = len < 1e-3 || lo < 1e-3 || own_covers_at(u);
                g_near_free += own_moves && near && !covers ? w : 0.0;
                add(BETWEEN, c, between ? w : 0.0);
                g_far_sum += between ? c : vec3(0.0);
                g_far_count += between ? 1.0 : 0.0;
            }
        }
    }
#endif
#else
    // The neighbourhood's line: what passes over the pixel; where merged, only its ends
    // beyond the own line, about as densely as the whole line's taps (rounded to the
    // nearest count, at least one a side: under a pan the ends are a few pixels long, and
    // a second tap each costs time for no gain in quality), and the own
    // object's fragments there count. (llvmpipe pays for a branch in a loop whether taken or not:
    // each tap fetches its colour once, unconditionally, and every bucket takes it with a
    // weight of 0 or w.)
#if SIMPLE
    rn = merged ? rn : 0.0;
#endif
    float R = max(rn, merged ? ro : 0.0);
    float gap = merged ? 2.0 * ro : 0.0;
    int n = taps_for(rn);
    int n_end = !merged ? n / 2 : R - ro > 1e-3
        ? max(1, int(floor((R - ro) * float(n) / (2.0 * rn) + 0.5))) : 0;
    n = merged ? 2 * n_end : n;
    if (rn > 0.5 && n > 0) {
        vec2 dir = vn / ln;
        for (int i = 0; i < n; ++i) {
            ivec2 y = tap_gap(x, dir, R, gap, i, n, n_end, a, b);
            vec4 m = texelFetch(u_front, y, 0);       // only |D| is needed: clamp that
            vec3 c = texelFetch(u_front_color, y, 0).rgb;
            float len = min(length(m.xy), u_max_disp);
            float w = coverage(a, b, len);
            bool own = m.w == own_id;
            add(OWN, c, own && merged ? w : 0.0);
#if !SIMPLE
            bool near = !own && m.z < own_depth;
            bool between = !own && !near && m.w != back_id && m.z < back_depth;
            add(NEAR, c, near ? w : 0.0);
            g_near_free += own_moves && near && !own_covers(len, lo) ? w : 0.0;
            add(BETWEEN, c, between ? w : 0.0);
            g_far_sum += between ? c : vec3(0.0);
            g_far_count += between ? 1.0 : 0.0;
#endif
        }
    }
#endif
    // The revealed layer's line, blurred along its own motion (merged with the raster
    // where nothing was revealed, so the line may run out of the mask).
    vec3 fill = g_far_count > 0.0 ? g_far_sum / g_far_count : own_colour;
    vec3 back_all = vec3(0.0);      // the line's background without the time pairing
    float back_all_w = 0.0;
#if BACK_LAYER
    if (revealed) {
        fill = back_colour(x);
        float rb = 0.5 * length(bx.xy);
        if (rb > 0.5) {
            vec2 dir = bx.xy / length(bx.xy);
            int n = taps_for(rb);
            for (int i = 0; i < n; ++i) {
                ivec2 y = tap(x, dir, rb, i, n, a, b);
                // The back layer there, or where nothing was revealed the front one
                // (back_motion and back_colour, with the front fetched once).
                vec4 f = front_motion(y);
                vec4 m = texelFetch(u_back, y, 0);
                vec4 cb = texelFetch(u_back_color, y, 0);
                vec3 c = cb.a > 0.5 ? cb.rgb : front_colour(y);
                // The revealed object itself (a slanted one is nearer in places) or
                // anything behind it; not the own object or others in front.
                float id = m.w > 0.5 ? m.w - 1.0 : f.w;
                m = m.w > 0.5 ? m : vec4(f.xyz, 0.0);
                if (id != back_id && m.z < back_depth * 0.999) continue;
                float len = min(length(m.xy), u_max_disp);
                float w = coverage(a, b, len);
                back_all += w * c;
                back_all_w += w;
                // The background seen at x is this fragment at the time u = -s / |m| it
                // passes x; it counts only if the own object does not cover x then (the
                // own fragment that would be at x then is at x - u D, frame time). With a
                // still background every time sees the same fragment: no pairing.
                w = own_moves && len >= 1e-3 && own_covers(len, lo) ? 0.0 : w;
                add(BACK, c, w);
            }
        } else {
            add(BACK, fill, 1.0);
        }
    }
#endif
    // The background's coverage is the whole line's; its colour, the paired taps' mean
    // (what shows while the own object is away), or the whole line's if none is paired.
    if (back_all_w > 0.0) {
        vec3 mean = g_weight[BACK] > 0.0 ? g_sum[BACK] / g_weight[BACK] : back_all / back_all_w;
        g_weight[BACK] = min(1.0, back_all_w);
        g_sum[BACK] = mean * g_weight[BACK];
    }
    vec3 c = over(BACK, fill);
    c = over(BETWEEN, c);
    // Own object and nearer fragments: "over" where the nearer ones pass in front of the
    // own object, side by side where they cover the pixel while the own object is away
    // (surfaces sliding together under a moving camera): own shows for a_o of the time
    // less the nearer ones' time over it, the rest for what neither covers.
    float a_n = min(1.0, g_weight[NEAR]);
    float a_o = min(1.0, g_weight[OWN]);
    float a_free = min(g_near_free, a_n);
    float vis_own = max(a_o - (a_n - a_free), 0.0);
    float vis_rest = max(1.0 - a_n - vis_own, 0.0);
    vec3 near_c = g_weight[NEAR] > 0.0 ? g_sum[NEAR] / g_weight[NEAR] : vec3(0.0);
    vec3 own_c = g_weight[OWN] > 0.0 ? g_sum[OWN] / g_weight[OWN] : vec3(0.0);
    c = (a_n * near_c + vis_own * own_c + vis_rest * c) / max(a_n + vis_own + vis_rest, 1e-6);
    out_color = vec4(c, 1.0);
}
