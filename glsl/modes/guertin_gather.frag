#version 330 core
// Guertin, McGuire, Nowrouzezahrai 2014, "A Fast and Stable Feature-Aware Motion Blur
// Filter" (HPG 2014), the reconstruction of its Appendix A, restated for positive linear
// depth. Against McGuire 2012:
//  - NeighborMax is read at a pixel offset along one axis (chosen per pixel) by up to
//    u_tile_jitter tiles, never into a diagonal tile: tile seams turn into noise, and the
//    tile read, an axis neighbour at most, still counts this pixel's own tile, so |vN| is
//    at least |vC| (a diagonal tile's NeighborMax may have dropped it by the diagonal rule);
//  - taps alternate between the neighbourhood direction wN (even taps, the outermost
//    two among them) and a centre direction wC (odd taps), the pixel's own direction
//    blended toward the perpendicular of wN as the pixel slows (below 0.5 + gamma px):
//    slow and static detail is sampled across the dominant motion and stays sharp (the
//    "feature-aware" part); every tap lies t |vN| from X and is weighed at that
//    unrounded distance T, as in the paper;
//  - one low-discrepancy jitter per pixel (interleaved gradient noise) shifts every tap
//    by up to eta * phi / N tap spacings;
//  - each case of the weight is scaled by how well the tap's direction matches the
//    velocity whose spread it uses;
//  - the centre weight is N / (kappa |vC|), so a fast thin object does not turn opaque;
//    with u_skip_middle (odd N) the middle tap, about X itself, is left to it, as McGuire
//    2012 and McGuire's G3D gather do;
//  - the depth compare is relative to the nearer depth instead of a fixed extent.
// With a path (SEGMENTS > 1, glsl/passes/path.glsl), the neighbourhood taps follow the
// NeighborMax winner's path as in glsl/modes/mcguire_gather.frag: tap t at time u = -t/2, at
// X - oN(u), its direction the piece's, its weights from the distance |u| K |piece| and
// the tap's and X's own pieces of that segment; the centre-direction taps of a pixel whose
// wC is its own direction walk its own path the same way (scaled to the neighbourhood's
// reach), those of slower pixels stay straight along wC (wN: glsl/passes/path.glsl
// path_direction). The early out and the tap reach take the path's half extent, X's
// centre weight the half extent of its own path.
#include "graph/noise.glsl"
#if SEGMENTS > 1
#define PATH_READ
#define PATH_TILES_READ
#include "passes/path.glsl"
#endif
uniform sampler2D u_color;
uniform sampler2D u_depth;
uniform sampler2D u_velocity;      // half vectors, clamped to [0.5, r] px (or zero)
uniform sampler2D u_neighbormax;   // (diagonal rule applied)
uniform int u_tile;                // r: tile size = blur limit
uniform int u_samples;             // N
uniform float u_gamma;             // px over 0.5 where the centre direction is the pixel's own
uniform float u_kappa;             // centre weight divisor
uniform float u_eta;               // tap jitter scale
uniform float u_phi;               // tap count at which the jitter spans eta tap spacings
uniform bool u_skip_middle;        // leave the middle tap (odd N) to the centre weight
uniform float u_tile_jitter;       // largest NeighborMax lookup offset, in tiles
uniform float u_z_scale;           // depth compare extent, as a fraction of the nearer depth
out vec4 out_color;

// 1 when A is nearer than B, falling to 0 once A lies u_z_scale * min(A, B) behind it.
float front(float depth_a, float depth_b) {
    return clamp(1.0 - (depth_a - depth_b) / (u_z_scale * min(depth_a, depth_b)), 0.0, 1.0);
}

float cone(float dist, float r) { return clamp(1.0 - dist / r, 0.0, 1.0); }

float cylinder(float dist, float r) { return 1.0 - smoothstep(0.95 * r, 1.05 * r, dist); }

// The PSF radius of a velocity: at least half a pixel (the velocity clamp's floor).
float radius(vec2 v) { return max(length(v), 0.5); }

// The direction of v, or 0 for a still pixel (which has none to align with).
vec2 direction(vec2 v) { float l = length(v); return l > 0.0 ? v / l : vec2(0.0); }

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_color, 0);
    vec4 cx = texelFetch(u_color, x, 0);
    float shift = u_tile_jitter * float(u_tile) * (2.0 * hash01(x, TILE_STREAM_X) - 1.0);
    vec2 offset = hash01(x, TILE_STREAM_Y) < 0.5 ? vec2(shift, 0.0) : vec2(0.0, shift);
    ivec2 q = clamp(ivec2(floor(vec2(x) + 0.5 + offset)), ivec2(0), size - 1);
#if SEGMENTS > 1
    vec2 on[PATH_POINTS], ox[PATH_POINTS], os[PATH_POINTS];
    tile_path(q / u_tile, on);
    float ln = 0.5 * path_extent(on);
    if (ln <= EARLY_OUT_PX) {
        out_color = cx;
        return;
    }
    float limit = float(u_tile);
    clamp_path(on, 2.0 * limit);
    ln = min(ln, limit);
    front_path_raw(x, ox);
    clamp_path(ox, 2.0 * limit);
    vec2 wn = path_direction(on);      // (not 0: the path's extent passed the early out)
    vec2 vc = texelFetch(u_velocity, x, 0).xy;
    float rc = clamp(0.5 * path_extent(ox), 0.5, limit);
#else
    vec2 vn = texelFetch(u_neighbormax, q / u_tile, 0).xy;
    float ln = length(vn);
    if (ln <= EARLY_OUT_PX) {          // nothing in reach moves: keep the pixel
        out_color = cx;
        return;
    }
    vec2 wn = vn / ln;
    vec2 vc = texelFetch(u_velocity, x, 0).xy;
    float rc = radius(vc);
#endif
    float zc = texelFetch(u_depth, x, 0).x;
    vec2 wp = vec2(-wn.y, wn.x);
    if (dot(wp, vc) < 0.0) wp = -wp;
    float own = clamp((length(vc) - 0.5) / u_gamma, 0.0, 1.0);
    vec2 wc = normalize(mix(wp, direction(vc), own));
#if SEGMENTS > 1
    // A pixel fast enough that wC is its own direction walks its own path instead,
    // scaled to the neighbourhood's reach ln (X - oX(u) ln / hX: X + t ln wC when straight).
    float hx = 0.5 * path_extent(ox);
    bool own_path = own >= 1.0 && hx > 0.0;
#endif
    float total = float(u_samples) / (u_kappa * rc);
    vec3 sum = total * cx.rgb;
    float j = u_eta * u_phi / float(u_samples) * (2.0 * ign(vec2(x), TAP_NOISE) - 1.0);
    int middle = u_skip_middle && u_samples % 2 == 1 ? (u_samples - 1) / 2 : -1;
    for (int i = 0; i < u_samples; ++i) {
        if (i == middle) continue;
        float t = -1.0 + 2.0 * (float(i) + 1.0 + j) / float(u_samples + 1);
        bool along_n = i % 2 == 0;
        vec2 d = along_n ? wn : wc;
        ivec2 s = clamp(ivec2(floor(vec2(x) + 0.5 + (t * ln) * d)), ivec2(0), size - 1);
        float dist = abs(t) * ln;
        vec2 vs = texelFetch(u_velocity, s, 0).xy;
        float rs = radius(vs);
        float rcs = rc;
        vec2 ws = direction(vs);
#if SEGMENTS > 1
        if (along_n || own_path) {     // along the neighbourhood's or the pixel's path
            float u = -0.5 * t;
            int k = path_segment(u);
            float scale = along_n ? 1.0 : ln / hx;
            vec2 piece = (along_n ? on[k + 1] - on[k] : ox[k + 1] - ox[k]) * scale;
            vec2 at = (along_n ? path_at(on, u) : path_at(ox, u)) * scale;
            d = direction(piece);
            s = clamp(ivec2(floor(vec2(x) + 0.5 - at)), ivec2(0), size - 1);
            dist = abs(u) * float(SEGMENTS) * length(piece);
            front_path_raw(s, os);
            clamp_path(os, 2.0 * limit);
            rs = piece_radius(os, k, limit);
            rcs = piece_radius(ox, k, limit);
            ws = direction(os[k + 1] - os[k]);
        }
#endif
        float zs = texelFetch(u_depth, s, 0).x;
        float wa = abs(dot(wc, d));
        float wb = abs(dot(ws, d));
        float a = front(zs, zc) * cone(dist, rs) * wb           // S in front of X
                + front(zc, zs) * cone(dist, rcs) * wa          // S behind a blurry X
                + 2.0 * cylinder(dist, min(rs, rcs)) * max(wa, wb);
        total += a;
        sum += a * texelFetch(u_color, s, 0).rgb;
    }
    out_color = vec4(sum / total, 1.0);
}
