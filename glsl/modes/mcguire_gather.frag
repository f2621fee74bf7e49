#version 330 core
// McGuire, Hennessy, Bukowski, Osman 2012 reconstruction (docs/algorithms.md 1.4), restated
// for positive linear depth. S taps along the neighbourhood's dominant half vector vN,
// jittered per pixel, rounded to pixel centres and clamped to the screen; each tap is
// weighted by the three cases of the paper: a blurry tap in front of X (its cone), a tap
// behind a blurry X (X's cone), and both blurry (2 * cylinder * cylinder).
// With a path (SEGMENTS > 1, glsl/passes/path.glsl): tap t lands at time u = -t/2 of the
// neighbourhood's path, at X - oN(u), so each segment holds its share of the exposure and
// of the taps; its weights take the distance |u| K |piece of N| and the radii of the
// tap's and X's own pieces of that segment (the paper's weights for a straight motion at
// the piece's speed); X's centre weight the half extent of its path. The early out tests
// the neighbourhood path's half extent.
#include "graph/noise.glsl"
#if SEGMENTS > 1
#define PATH_READ
#define PATH_TILES_READ
#include "passes/path.glsl"
#endif
uniform sampler2D u_color;
uniform sampler2D u_depth;
uniform sampler2D u_velocity;      // half vectors, clamped to [0.5, k] px (or zero)
uniform sampler2D u_neighbormax;
uniform int u_tile;                // k
uniform int u_samples;             // S, odd
uniform float u_soft_z;            // SOFT_Z_EXTENT, metres
uniform float u_jitter;            // 0: fixed taps, 1: the paper's j in [-0.5, 0.5)
uniform float u_kappa;             // 0: centre weight 1/|V| (paper); else S/(kappa |V|)
out vec4 out_color;

// 1 when A is nearer than B or within about SOFT_Z_EXTENT behind it, 0 when A is farther
// by SOFT_Z_EXTENT or more (the paper's softDepthCompare with its negative z negated).
float front(float depth_a, float depth_b) {
    return clamp(1.0 - (depth_a - depth_b) / u_soft_z, 0.0, 1.0);
}

float cone(float dist, float r) { return clamp(1.0 - dist / r, 0.0, 1.0); }

float cylinder(float dist, float r) { return 1.0 - smoothstep(0.95 * r, 1.05 * r, dist); }

// The PSF radius of a velocity: at least half a pixel, so 1/r stays finite.
float radius(vec2 v) { return max(length(v), 0.5); }

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_color, 0);
    vec4 cx = texelFetch(u_color, x, 0);
#if SEGMENTS > 1
    vec2 on[PATH_POINTS], ox[PATH_POINTS], oy[PATH_POINTS];
    tile_path(x / u_tile, on);
    if (0.5 * path_extent(on) <= EARLY_OUT_PX) {
        out_color = cx;
        return;
    }
    float limit = float(u_tile);
    clamp_path(on, 2.0 * limit);
    front_path_raw(x, ox);
    clamp_path(ox, 2.0 * limit);
    float rx = clamp(0.5 * path_extent(ox), 0.5, limit);
#else
    vec2 vn = texelFetch(u_neighbormax, x / u_tile, 0).xy;
    if (length(vn) <= EARLY_OUT_PX) {      // nothing in reach moves: keep the pixel
        out_color = cx;
        return;
    }
    float rx = radius(texelFetch(u_velocity, x, 0).xy);
#endif
    float zx = texelFetch(u_depth, x, 0).x;
    float weight = u_kappa > 0.0 ? float(u_samples) / (u_kappa * rx) : 1.0 / rx;
    vec3 sum = weight * cx.rgb;
    float j = u_jitter * (hash01(x, JITTER_STREAM) - 0.5);
    int middle = (u_samples - 1) / 2;      // ~ the centre, already counted above
#if CENTRE_ONLY
    // Drawn only where every tap off the pixel weighs exactly 0 (viewer/render/
    // gather_reach.py): a tap that lands on the pixel weighs what the loop's terms give
    // there (Y = X, distance 0), and reads nothing.
    float own = front(zx, zx) * cone(0.0, rx) + front(zx, zx) * cone(0.0, rx)
              + 2.0 * cylinder(0.0, rx) * cylinder(0.0, rx);
#endif
    for (int i = 0; i < u_samples; ++i) {
        if (i == middle) continue;
        float t = -1.0 + 2.0 * (float(i) + j + 1.0) / float(u_samples + 1);
#if SEGMENTS > 1
        float u = -0.5 * t;
        int s = path_segment(u);
        ivec2 y = clamp(ivec2(floor(vec2(x) + 0.5 - path_at(on, u))), ivec2(0), size - 1);
        float dist = abs(u) * float(SEGMENTS) * length(on[s + 1] - on[s]);
        front_path_raw(y, oy);
        clamp_path(oy, 2.0 * limit);
        float ry = piece_radius(oy, s, limit);
        float rxs = piece_radius(ox, s, limit);
#else
        ivec2 y = clamp(ivec2(floor(vec2(x) + 0.5 + t * vn)), ivec2(0), size - 1);
#if CENTRE_ONLY
        if (y == x) {
            weight += own;
            sum += own * cx.rgb;
        }
        continue;
#endif
        float dist = length(vec2(y - x));
        float ry = radius(texelFetch(u_velocity, y, 0).xy);
        float rxs = rx;
#endif
        float zy = texelFetch(u_depth, y, 0).x;
        float a = front(zy, zx) * cone(dist, ry)          // Y in front of X
                + front(zx, zy) * cone(dist, rxs)         // Y behind a blurry X
                + 2.0 * cylinder(dist, ry) * cylinder(dist, rxs);
        weight += a;
        sum += a * texelFetch(u_color, y, 0).rgb;
    }
    out_color = vec4(sum / weight, 1.0);
}
