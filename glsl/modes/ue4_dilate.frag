#version 330 core
// Dilation by swept quads (docs/algorithms.md 3.2 b), as a gather: tile n covers this tile m
// when m lies in the quad swept by n's max velocity (in tiles) along its direction, with
// half-length |v_t| + e and half-width e, e = 0.99 (|dir.x| + |dir.y|); a tile slower than
// half a pixel covers only itself. Covered tiles merge min-of-mins and max-of-maxes.
// With a path (SEGMENTS > 1) the path of the max's tile is carried (out_path0/1).
uniform sampler2D u_tiles;      // (vmin.xy, vmax.xy), px
uniform float u_tile;           // tile size, px
uniform int u_reach;            // window half-size in tiles (covers the blur limit)
uniform bool u_guard;           // also take the min over every tile a tap can read
uniform float u_tile_jitter;    // the gather's tile-lookup jitter, tiles
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
    ivec2 grid = textureSize(u_tiles, 0);
    ivec2 m = ivec2(gl_FragCoord.xy);
    ivec2 lo = max(m - u_reach, ivec2(0)), hi = min(m + u_reach, grid - 1);
    vec2 vmin = vec2(0.0), vmax = vec2(0.0);
    float lmin = 3.0e38, lmax = 0.0;      // any velocity replaces the initial min
    ivec2 at = m;
    for (int y = lo.y; y <= hi.y; ++y) {
        for (int x = lo.x; x <= hi.x; ++x) {
            ivec2 n = ivec2(x, y);
            vec4 t = texelFetch(u_tiles, n, 0);
            float l2 = dot(t.zw, t.zw);
            bool covers;
            if (l2 < 0.25) {
                covers = n == m;
            } else {
                float len = sqrt(l2);
                vec2 dir = t.zw / len;
                float e = 0.99 * (abs(dir.x) + abs(dir.y));
                vec2 o = vec2(m - n);
                covers = abs(dot(o, dir)) < len / u_tile + e
                      && abs(dot(o, vec2(-dir.y, dir.x))) < e;
            }
            if (!covers) continue;
            float n2 = dot(t.xy, t.xy);
            if (n2 < lmin) { lmin = n2; vmin = t.xy; }
            if (l2 > lmax) { lmax = l2; vmax = t.zw; at = n; }
        }
    }
    if (u_guard) {
        // A tile slower than half a pixel covers only itself, so a uniformly moving tile
        // beside a screen-static one keeps a large min and would take the fast path,
        // averaging the static pixels its taps reach. Pixels that look this tile up lie
        // within tile_jitter tiles of it and read up to |vmax| px farther.
        int r = int(ceil(length(vmax) / u_tile + u_tile_jitter));
        ivec2 glo = max(m - r, ivec2(0)), ghi = min(m + r, grid - 1);
        for (int y = glo.y; y <= ghi.y; ++y) {
            for (int x = glo.x; x <= ghi.x; ++x) {
                vec2 tmin = texelFetch(u_tiles, ivec2(x, y), 0).xy;
                float n2 = dot(tmin, tmin);
                if (n2 < lmin) { lmin = n2; vmin = tmin; }
            }
        }
    }
    out_tiles = vec4(vmin, vmax);
#if SEGMENTS > 1
    out_path0 = texelFetch(u_path0, at, 0);
#if SEGMENTS == 4
    out_path1 = texelFetch(u_path1, at, 0);
#endif
#endif
}
