#version 330 core
// One separable TileMax step (docs/algorithms.md 1.2): the velocity of largest magnitude over
// u_tile texels of the source along u_axis, starting at this texel's tile. Texels past the
// source's edge (a partial last tile) are skipped. Ties keep the first texel in scan order.
// With a path (SEGMENTS > 1, glsl/passes/path.glsl: u_path0/u_path1 the full-size path targets or
// the previous step's), the winner is the texel of longest path extent, and its path is
// written too (out_path0/out_path1); out_max is then its chord.
uniform sampler2D u_velocity;
uniform int u_tile;
uniform ivec2 u_axis;          // (1, 0): k x 1, full width -> strip; (0, 1): 1 x k
layout(location = 0) out vec2 out_max;
#if SEGMENTS > 1
#define PATH_READ
#include "passes/path.glsl"
layout(location = 1) out vec4 out_path0;
#if SEGMENTS == 4
layout(location = 2) out vec4 out_path1;
#endif
#endif

void main() {
    ivec2 t = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_velocity, 0);
    // Along the axis the texel index is a tile index; across it, the same row/column.
    ivec2 start = t * (ivec2(1) - u_axis) + t * u_axis * u_tile;
    vec2 best = vec2(0.0);
    float best2 = -1.0;
#if SEGMENTS > 1
    vec4 best_p0 = vec4(0.0), best_p1 = vec4(0.0);
#endif
    for (int i = 0; i < u_tile; ++i) {
        ivec2 p = start + u_axis * i;
        if (p.x >= size.x || p.y >= size.y) break;
#if SEGMENTS > 1
        vec2 o[PATH_POINTS];
        front_path_raw(p, o);
        float m2 = path_extent(o);
        if (m2 > best2) {
            best = o[SEGMENTS] - o[0];
            best2 = m2;
            best_p0 = texelFetch(u_path0, p, 0);
#if SEGMENTS == 4
            best_p1 = texelFetch(u_path1, p, 0);
#endif
        }
#else
        vec2 v = texelFetch(u_velocity, p, 0).xy;
        float m2 = dot(v, v);
        if (m2 > best2) { best = v; best2 = m2; }
#endif
    }
    out_max = best;
#if SEGMENTS > 1
    out_path0 = best_p0;
#if SEGMENTS == 4
    out_path1 = best_p1;
#endif
#endif
}
