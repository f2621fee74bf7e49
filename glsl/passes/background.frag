#version 330 core
// Fills the G-buffer where nothing is hit (drawn first, without depth test).
#include "passes/gbuffer_outputs.glsl"
uniform vec3 u_background;
void main() {
    write_gbuffer(u_background, BACKGROUND_DEPTH, vec3(0.0), 0u, vec2(0.0));
#if SEGMENTS > 1
    out_path0 = vec4(0.0);              // the sky: no motion
#if SEGMENTS == 4
    out_path1 = vec4(0.0);
#endif
#endif
#ifdef RANK_LOCATION
    out_rank = 0u;
#endif
}
