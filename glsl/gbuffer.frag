#version 330 core
#include "shading.glsl"
#include "motion.glsl"
#include "gbuffer_outputs.glsl"

in vec3 v_local;
in vec3 v_normal_local;
in vec2 v_uv;
in vec3 v_world;
in vec4 v_view;
in vec4 v_view_open;
in vec4 v_view_close;

uniform mat3 u_normal_matrix;   // inverse transpose of M(t)'s upper 3x3
uniform uint u_object_id;

void main() {
    // (positions relative to the eye: the eye is the origin)
    vec3 n = unit_or_zero(u_normal_matrix * v_normal_local);
    if (dot(n, -v_world) < 0.0) n = -n;
    vec3 color = shade(v_world, n, v_local, v_uv);
#if GBUFFER_MOTION
    vec2 velocity = displacement_between(v_view_open, v_view_close, v_view);
#else
    vec2 velocity = vec2(0.0);
#endif
    write_gbuffer(color, -v_view.z, n, u_object_id, velocity);
}
