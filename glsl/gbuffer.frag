#version 330 core
#include "shading.glsl"
#include "motion.glsl"

in vec3 v_local;
in vec3 v_normal_local;
in vec2 v_uv;
in vec3 v_world;
in vec4 v_view;

uniform mat3 u_normal_matrix;   // inverse transpose of M(t)'s upper 3x3
uniform vec3 u_eye;
uniform uint u_object_id;

layout(location = 0) out vec4 out_color;     // linear, unclamped
layout(location = 1) out float out_depth;    // linear view depth
layout(location = 2) out vec4 out_normal;    // world normal, facing the camera
layout(location = 3) out uint out_id;        // object id (0 = background)
layout(location = 4) out vec2 out_velocity;  // pixels over the exposure, GL axes

void main() {
    vec3 n = normalize(u_normal_matrix * v_normal_local);
    if (dot(n, u_eye - v_world) < 0.0) n = -n;
    out_color = vec4(shade(v_world, n, v_local, v_uv, u_eye), 1.0);
    out_depth = -v_view.z;
    out_normal = vec4(n, 0.0);
    out_id = u_object_id;
    out_velocity = exposure_displacement(v_local, v_view);
}
