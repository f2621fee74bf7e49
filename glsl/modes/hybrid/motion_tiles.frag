#version 330 core
// Per u_tile x u_tile tile of the G-buffer's hybrid_front (D, depth, id), for the host's
// tile lists (viewer/render/modes/hybrid/tile_select.py): .x the longest displacement |D| (px over the
// exposure), .y 1 where the tile may hold an id boundary (a pixel whose right or upper
// neighbour shows another object), else 0. Two separable steps so the reads spread over
// many fragments: STAGE 0 over u_tile texels along x (full size -> strip), STAGE 1 over
// u_tile strip texels along y. length() is the one the ray mask passes compare with
// hybrid.min_speed, so a tile holds a moving pixel exactly when .x reaches that speed.
// Texels past the screen are skipped. With a path (SEGMENTS > 1, glsl/passes/path.glsl) .x is
// the longest path extent instead (twice the farthest point from the frame-time
// position), what the ray mask then compares: a reversal's chord is short, not its path.
//
// The strip carries (longest, id of the run, or -1 where the run holds two ids or its
// last pixel's right neighbour another): two runs one above the other with the same id
// (not -1) have no boundary between them; anything else counts as one (conservative).
uniform sampler2D u_source;
uniform int u_tile;
out vec2 out_tile;
#if SEGMENTS > 1 && STAGE == 0
#define PATH_READ
#include "passes/path.glsl"
#endif

void main() {
    ivec2 size = textureSize(u_source, 0);
    ivec2 p = ivec2(gl_FragCoord.xy);
#if STAGE == 0
    int x0 = p.x * u_tile, x1 = min(x0 + u_tile, size.x);
    float m = 0.0;
    float first = texelFetch(u_source, ivec2(x0, p.y), 0).w;
    bool mixed = false;
    for (int x = x0; x < x1; ++x) {
        vec4 f = texelFetch(u_source, ivec2(x, p.y), 0);
#if SEGMENTS > 1
        vec2 o[PATH_POINTS];
        front_path_raw(ivec2(x, p.y), o);
        m = max(m, path_extent(o));
#else
        m = max(m, length(f.xy));
#endif
        mixed = mixed || f.w != first;
    }
    if (x1 < size.x) mixed = mixed || texelFetch(u_source, ivec2(x1, p.y), 0).w != first;
    out_tile = vec2(m, mixed ? -1.0 : first);
#else
    int y0 = p.y * u_tile, y1 = min(y0 + u_tile, size.y);
    float m = 0.0;
    float first = texelFetch(u_source, ivec2(p.x, y0), 0).y;
    bool boundary = first < 0.0;
    for (int y = y0; y < y1; ++y) {
        vec2 s = texelFetch(u_source, ivec2(p.x, y), 0).xy;
        m = max(m, s.x);
        boundary = boundary || s.y != first;
    }
    if (y1 < size.y) boundary = boundary || texelFetch(u_source, ivec2(p.x, y1), 0).y != first;
    out_tile = vec2(m, boundary ? 1.0 : 0.0);
#endif
}
