#version 330 core
// UE4-style flatten: the half vector v = D/2 (the filter blurs from -v to +v), its length
// clamped to the shared blur limit, packed with the linear depth: (v.x, v.y, depth, |v|).
// With a path (SEGMENTS > 1, glsl/passes/path.glsl), |v| is the path's half extent (the farthest
// the surface goes) and v points along glsl/passes/path.glsl path_direction, so tiles, dilation
// and the early out cover the path; the gather walks the tile's path itself.
#if SEGMENTS > 1
#define PATH_READ
#include "passes/path.glsl"
#endif
uniform sampler2D u_velocity;   // full displacement D over the exposure, px, y up
uniform sampler2D u_depth;      // positive linear view depth, m
uniform float u_max_px;         // blur limit per side, px
out vec4 out_flat;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
#if SEGMENTS > 1
    vec2 o[PATH_POINTS];
    front_path_raw(p, o);
    float len = 0.5 * path_extent(o);
    vec2 v = len * path_direction(o);
#else
    vec2 v = 0.5 * texelFetch(u_velocity, p, 0).xy;
    float len = length(v);
#endif
    if (len > u_max_px) {
        v *= u_max_px / len;
        len = u_max_px;
    }
    out_flat = vec4(v, texelFetch(u_depth, p, 0).r, len);
}
