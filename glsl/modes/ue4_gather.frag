#version 330 core
// UE4-style gather (Jimenez 2014; docs/algorithms.md 3.2 c, 3.4). Taps come in pairs at
// X + o+/K vmax and X - o-/K vmax with opposite jitter; each tap is weighted by a depth
// compare (background taps use the centre's spread, foreground taps their own) and a box
// spread compare with a one-step edge; the mirror rule exchanges weights within a pair; the
// result is normalised by the tap count with the centre colour filling the rest.
// With a path (SEGMENTS > 1, glsl/passes/path.glsl), a tap o steps out lands at time
// u = -+o / 2K of the looked-up tile's path, at X - oT(u) (X +- o/K vmax when straight):
// each segment holds its share of the exposure and of the taps, and a tap's spread compare
// takes the tap's and the centre's own pieces of its segment, at that segment's step size.
#include "graph/noise.glsl"
#if SEGMENTS > 1
#define PATH_READ
#define PATH_TILES_READ
#include "passes/path.glsl"
uniform float u_max_px;         // the blur limit per side, px

// A piece's half vector length, as the flatten's |v| of a straight motion at its speed.
float piece_half(vec2 o[PATH_POINTS], int s) {
    return min(0.5 * float(SEGMENTS) * length(o[s + 1] - o[s]), u_max_px);
}
#endif
uniform sampler2D u_color;      // linear colour
uniform sampler2D u_flat;       // (v.x, v.y, depth, |v|), px and m
uniform sampler2D u_tiles;      // dilated (vmin.xy, vmax.xy), px
uniform int u_tile;
uniform int u_taps;             // K, taps per side
uniform float u_depth_scale;    // per metre
uniform float u_tile_jitter;    // tiles
uniform float u_tap_jitter;     // fraction of a step
uniform bool u_fast_path;
uniform float u_fast_ratio;
uniform bool u_mirror;
uniform bool u_bilinear;        // colour taps filtered (UE) or from the texel holding them
out vec4 out_color;

ivec2 g_size;

// Window-space point p (pixel centres at +0.5), clamped to the centres of the edge pixels.
vec2 clamp_tap(vec2 p) {
    return clamp(p, vec2(0.5), vec2(g_size) - 0.5);
}

// Colour at tap p: bilinear from the four texels around it, weighted here (see
// viewer/render/modes/ue4.py), or the texel that holds it, whose depth and velocity the weights use.
vec3 tap_color(vec2 p) {
    if (!u_bilinear) return texelFetch(u_color, ivec2(p), 0).rgb;
    vec2 q = p - 0.5;
    ivec2 i0 = ivec2(floor(q));
    vec2 f = q - vec2(i0);
    ivec2 i1 = min(i0 + 1, g_size - 1);
    vec3 c00 = texelFetch(u_color, i0, 0).rgb;
    vec3 c10 = texelFetch(u_color, ivec2(i1.x, i0.y), 0).rgb;
    vec3 c01 = texelFetch(u_color, ivec2(i0.x, i1.y), 0).rgb;
    vec3 c11 = texelFetch(u_color, i1, 0).rgb;
    return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}

// Weight of one tap at `o` steps from the centre: background (farther) taps count where
// the centre's own blur reaches them, foreground taps where their blur reaches the centre.
// The spread edge uses this tap's own offset (UE reuses o+ for both taps of a pair; with
// opposite jitter that moves the o- tap's edge by up to one step).
float tap_weight(vec4 centre, vec4 tap, float o, float px_to_step) {
    float dz = tap.z - centre.z;
    vec2 depth_cmp = clamp(0.5 + vec2(u_depth_scale, -u_depth_scale) * dz, 0.0, 1.0);
    vec2 spread = clamp(px_to_step * vec2(centre.w, tap.w) - max(o - 1.0, 0.0), 0.0, 1.0);
    return dot(depth_cmp, spread);
}

void main() {
    g_size = textureSize(u_color, 0);
    vec2 X = gl_FragCoord.xy;
    ivec2 xi = ivec2(X);
    vec3 centre_color = texelFetch(u_color, xi, 0).rgb;

    vec2 jitter = vec2(ign(X, 1.0), ign(X, 2.0)) - 0.5;
    ivec2 grid = textureSize(u_tiles, 0);
    ivec2 t = clamp(ivec2(floor(X / float(u_tile) + 2.0 * u_tile_jitter * jitter)),
                    ivec2(0), grid - 1);
    vec4 tile = texelFetch(u_tiles, t, 0);
    vec2 vmin = tile.xy, vmax = tile.zw;
    float lmax2 = dot(vmax, vmax);
    if (lmax2 < EARLY_OUT_PX * EARLY_OUT_PX) {  // nothing here moves by half a pixel
        out_color = vec4(centre_color, 1.0);
        return;
    }

    float K = float(u_taps);
    float j = u_tap_jitter * (ign(X, 0.0) - 0.5);
#if SEGMENTS > 1
    vec2 on[PATH_POINTS], ox[PATH_POINTS], o0[PATH_POINTS], o1[PATH_POINTS];
    tile_path(t, on);
    clamp_path(on, 2.0 * u_max_px);
#endif
    if (u_fast_path && dot(vmin, vmin) > u_fast_ratio * lmax2) {
        vec3 sum = vec3(0.0);                   // uniform motion: a plain box average
        for (int i = 0; i < u_taps; ++i) {
            float op = float(i) + 0.5 + j, om = float(i) + 0.5 - j;
#if SEGMENTS > 1
            sum += tap_color(clamp_tap(X - path_at(on, -0.5 * op / K)));
            sum += tap_color(clamp_tap(X - path_at(on, 0.5 * om / K)));
#else
            sum += tap_color(clamp_tap(X + (op / K) * vmax));
            sum += tap_color(clamp_tap(X - (om / K) * vmax));
#endif
        }
        out_color = vec4(sum / (2.0 * K), 1.0);
        return;
    }

    vec4 centre = texelFetch(u_flat, xi, 0);
    float px_to_step = K / sqrt(lmax2);
    vec3 acc = vec3(0.0);
    float wsum = 0.0;
#if SEGMENTS > 1
    front_path_raw(xi, ox);
    clamp_path(ox, 2.0 * u_max_px);
#endif
    for (int i = 0; i < u_taps; ++i) {
        float op = float(i) + 0.5 + j, om = float(i) + 0.5 - j;
#if SEGMENTS > 1
        float u0 = -0.5 * op / K, u1 = 0.5 * om / K;
        int s0 = path_segment(u0), s1 = path_segment(u1);
        vec2 p0 = clamp_tap(X - path_at(on, u0));
        vec2 p1 = clamp_tap(X - path_at(on, u1));
        vec4 f0 = texelFetch(u_flat, ivec2(p0), 0);
        vec4 f1 = texelFetch(u_flat, ivec2(p1), 0);
        front_path_raw(ivec2(p0), o0);
        front_path_raw(ivec2(p1), o1);
        clamp_path(o0, 2.0 * u_max_px);
        clamp_path(o1, 2.0 * u_max_px);
        f0.w = piece_half(o0, s0);
        f1.w = piece_half(o1, s1);
        float w0 = tap_weight(vec4(centre.xyz, piece_half(ox, s0)), f0, op,
                              K / max(piece_half(on, s0), 1e-6));
        float w1 = tap_weight(vec4(centre.xyz, piece_half(ox, s1)), f1, om,
                              K / max(piece_half(on, s1), 1e-6));
#else
        vec2 p0 = clamp_tap(X + (op / K) * vmax);
        vec2 p1 = clamp_tap(X - (om / K) * vmax);
        vec4 f0 = texelFetch(u_flat, ivec2(p0), 0);
        vec4 f1 = texelFetch(u_flat, ivec2(p1), 0);
        float w0 = tap_weight(centre, f0, op, px_to_step);
        float w1 = tap_weight(centre, f1, om, px_to_step);
#endif
        if (u_mirror) {
            // the farther tap takes the nearer tap's weight when the nearer one is faster
            bool far0 = f0.z > f1.z, fast1 = f1.w > f0.w;
            if (far0 && fast1) w0 = w1;
            if (!far0 && !fast1) w1 = w0;
        }
        acc += w0 * tap_color(p0) + w1 * tap_color(p1);
        wsum += w0 + w1;
    }
    out_color = vec4(acc / (2.0 * K) + (1.0 - wsum / (2.0 * K)) * centre_color, 1.0);
}
