#version 330 core
// Fills the G-buffer where nothing is hit (drawn first, without depth test).
#include "gbuffer_outputs.glsl"
uniform vec3 u_background;
void main() {
    write_gbuffer(u_background, BACKGROUND_DEPTH, vec3(0.0), 0u, vec2(0.0));
}
