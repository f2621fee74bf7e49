#version 330 core
// NeighborMax (McGuire et al. 2012): the TileMax vector of largest magnitude over the 3x3
// tiles around this one, tiles outside the grid skipped. The centre is taken first and
// wins ties, so a neighbourhood of equal speeds keeps its own direction. With a path
// (SEGMENTS > 1, glsl/passes/tilemax.frag's path targets in u_path0/u_path1) the tile of longest
// path extent wins, and its path is written too.
// DIAGONAL_TOWARD 1 (Guertin et al. 2014): a diagonal neighbour at offset o counts only
// where its vector points toward this tile (dot(v, -o) > 0); its blur cannot reach this
// tile otherwise, and taking it would smear a corner across the tile.
uniform sampler2D u_tiles;
layout(location = 0) out vec2 out_max;
#if SEGMENTS > 1
#define PATH_READ
#include "passes/path.glsl"
layout(location = 1) out vec4 out_path0;
#if SEGMENTS == 4
layout(location = 2) out vec4 out_path1;
#endif

float extent_at(ivec2 p) {
    vec2 o[PATH_POINTS];
    front_path_raw(p, o);
    return path_extent(o);
}
#endif

void main() {
    ivec2 t = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_tiles, 0);
    vec2 best = texelFetch(u_tiles, t, 0).xy;
#if SEGMENTS > 1
    ivec2 at = t;
    float best2 = extent_at(t);
#else
    float best2 = dot(best, best);
#endif
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 p = t + ivec2(dx, dy);
            if (p.x < 0 || p.y < 0 || p.x >= size.x || p.y >= size.y) continue;
            vec2 v = texelFetch(u_tiles, p, 0).xy;
#if DIAGONAL_TOWARD
            if (dx != 0 && dy != 0 && dot(v, -vec2(dx, dy)) <= 0.0) continue;
#endif
#if SEGMENTS > 1
            float m2 = extent_at(p);
            if (m2 > best2) { best = v; best2 = m2; at = p; }
#else
            float m2 = dot(v, v);
            if (m2 > best2) { best = v; best2 = m2; }
#endif
        }
    }
    out_max = best;
#if SEGMENTS > 1
    out_path0 = texelFetch(u_path0, at, 0);
#if SEGMENTS == 4
    out_path1 = texelFetch(u_path1, at, 0);
#endif
#endif
}
