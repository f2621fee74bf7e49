#version 330 core
// Guertin, McGuire, Nowrouzezahrai 2014, "A Fast and Stable Feature-Aware Motion Blur
// Filter" (HPG 2014), the reconstruction of its Appendix A, restated for positive linear
// depth. Against McGuire 2012:
//  - NeighborMax is read at a jittered pixel (up to u_tile_jitter tiles per axis), which
//    turns tile seams into noise;
//  - taps alternate between the neighbourhood direction wN and a centre direction wC,
//    the pixel's own direction blended toward the perpendicular of wN as the pixel slows
//    (below 0.5 + gamma px): slow and static detail is sampled across the dominant motion
//    and stays sharp (the "feature-aware" part);
//  - each case of the weight is scaled by how well the tap's direction matches the
//    velocity whose spread it uses;
//  - the centre weight is N / (kappa |vC|), so a fast thin object does not turn opaque;
//  - the depth compare is relative to the nearer depth instead of a fixed extent.
#include "noise.glsl"
uniform sampler2D u_color;
uniform sampler2D u_depth;
uniform sampler2D u_velocity;      // half vectors, clamped to [0.5, r] px (or zero)
uniform sampler2D u_neighbormax;   // (diagonal rule applied)
uniform int u_tile;                // r: tile size = blur limit
uniform int u_samples;             // N
uniform float u_gamma;             // px over 0.5 where the centre direction is the pixel's own
uniform float u_kappa;             // centre weight divisor
uniform float u_eta;               // tap jitter scale
uniform float u_tile_jitter;       // largest NeighborMax lookup offset per axis, in tiles
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
    vec2 offset = u_tile_jitter * float(u_tile) *
                  (2.0 * vec2(hash01(x, TILE_STREAM_X), hash01(x, TILE_STREAM_Y)) - 1.0);
    ivec2 q = clamp(ivec2(floor(vec2(x) + 0.5 + offset)), ivec2(0), size - 1);
    vec2 vn = texelFetch(u_neighbormax, q / u_tile, 0).xy;
    float ln = length(vn);
    if (ln <= EARLY_OUT_PX) {          // nothing in reach moves: keep the pixel
        out_color = cx;
        return;
    }
    vec2 wn = vn / ln;
    vec2 vc = texelFetch(u_velocity, x, 0).xy;
    float rc = radius(vc);
    float zc = texelFetch(u_depth, x, 0).x;
    vec2 wp = vec2(-wn.y, wn.x);
    if (dot(wp, vc) < 0.0) wp = -wp;
    vec2 wc = normalize(mix(wp, direction(vc), clamp((length(vc) - 0.5) / u_gamma, 0.0, 1.0)));
    float total = float(u_samples) / (u_kappa * rc);
    vec3 sum = total * cx.rgb;
    float j = 2.0 * hash01(x, TAP_STREAM) - 1.0;
    for (int i = 0; i < u_samples; ++i) {
        float t = -1.0 + 2.0 * (float(i) + 1.0 + u_eta * j) / float(u_samples + 1);
        vec2 d = (i % 2 == 0) ? wc : wn;
        ivec2 s = clamp(ivec2(floor(vec2(x) + 0.5 + (t * ln) * d)), ivec2(0), size - 1);
        // The distance of the pixel read, as in McGuire 2012, not the unrounded |t| |vN|:
        // a tap 0.5 px out that rounds onto a neighbour would take the cylinder's soft
        // edge at r = 0.5 and smear still detail.
        float dist = length(vec2(s - x));
        vec2 vs = texelFetch(u_velocity, s, 0).xy;
        float rs = radius(vs);
        float zs = texelFetch(u_depth, s, 0).x;
        float wa = abs(dot(wc, d));
        float wb = abs(dot(direction(vs), d));
        float a = front(zs, zc) * cone(dist, rs) * wb           // S in front of X
                + front(zc, zs) * cone(dist, rc) * wa           // S behind a blurry X
                + 2.0 * cylinder(dist, min(rs, rc)) * max(wa, wb);
        total += a;
        sum += a * texelFetch(u_color, s, 0).rgb;
    }
    out_color = vec4(sum / total, 1.0);
}
