#version 330 core
// Per tile, the velocities of least and greatest length: (vmin.xy, vmax.xy), px.
// Pixels of a border tile that fall outside the screen take no part. Scan order (rows
// upward, then columns rightward) with strict compares settles ties, as the tests expect.
// With a path (SEGMENTS > 1) the max texel's path is written too (out_path0/1).
uniform sampler2D u_flat;       // (v.x, v.y, depth, |v|)
uniform int u_tile;
layout(location = 0) out vec4 out_tiles;
#if SEGMENTS > 1
#define PATH_READ
#include "passes/path.glsl"
layout(location = 1) out vec4 out_path0;
#if SEGMENTS == 4
layout(location = 2) out vec4 out_path1;
#endif
#endif

void main() {
    ivec2 size = textureSize(u_flat, 0);
    ivec2 base = ivec2(gl_FragCoord.xy) * u_tile;
    ivec2 end = min(base + u_tile, size);
    vec2 vmin = vec2(0.0), vmax = vec2(0.0);
    float lmin = 3.0e38, lmax = 0.0;      // any velocity replaces the initial min
    ivec2 at = base;
    for (int y = base.y; y < end.y; ++y) {
        for (int x = base.x; x < end.x; ++x) {
            vec4 f = texelFetch(u_flat, ivec2(x, y), 0);
            if (f.w < lmin) { lmin = f.w; vmin = f.xy; }
            if (f.w > lmax) { lmax = f.w; vmax = f.xy; at = ivec2(x, y); }
        }
    }
    out_tiles = vec4(vmin, vmax);
#if SEGMENTS > 1
    out_path0 = lmax > 0.0 ? texelFetch(u_path0, at, 0) : vec4(0.0);
#if SEGMENTS == 4
    out_path1 = lmax > 0.0 ? texelFetch(u_path1, at, 0) : vec4(0.0);
#endif
#endif
}
