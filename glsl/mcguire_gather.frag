#version 330 core
// McGuire, Hennessy, Bukowski, Osman 2012 reconstruction (ALGORITHMS.md 1.4), restated
// for positive linear depth. S taps along the neighbourhood's dominant half vector vN,
// jittered per pixel, rounded to pixel centres and clamped to the screen; each tap is
// weighted by the three cases of the paper: a blurry tap in front of X (its cone), a tap
// behind a blurry X (X's cone), and both blurry (2 * cylinder * cylinder).
#include "noise.glsl"
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
    vec2 vn = texelFetch(u_neighbormax, x / u_tile, 0).xy;
    if (length(vn) <= EARLY_OUT_PX) {      // nothing in reach moves: keep the pixel
        out_color = cx;
        return;
    }
    float zx = texelFetch(u_depth, x, 0).x;
    float rx = radius(texelFetch(u_velocity, x, 0).xy);
    float weight = u_kappa > 0.0 ? float(u_samples) / (u_kappa * rx) : 1.0 / rx;
    vec3 sum = weight * cx.rgb;
    float j = u_jitter * (hash01(x, JITTER_STREAM) - 0.5);
    int middle = (u_samples - 1) / 2;      // ~ the centre, already counted above
    for (int i = 0; i < u_samples; ++i) {
        if (i == middle) continue;
        float t = -1.0 + 2.0 * (float(i) + j + 1.0) / float(u_samples + 1);
        ivec2 y = clamp(ivec2(floor(vec2(x) + 0.5 + t * vn)), ivec2(0), size - 1);
        float dist = length(vec2(y - x));
        float zy = texelFetch(u_depth, y, 0).x;
        float ry = radius(texelFetch(u_velocity, y, 0).xy);
        float a = front(zy, zx) * cone(dist, ry)          // Y in front of X
                + front(zx, zy) * cone(dist, rx)          // Y behind a blurry X
                + 2.0 * cylinder(dist, ry) * cylinder(dist, rx);
        weight += a;
        sum += a * texelFetch(u_color, y, 0).rgb;
    }
    out_color = vec4(sum / weight, 1.0);
}
