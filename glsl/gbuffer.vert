#version 330 core
#include "motion.glsl"
// G-buffer geometry: mesh-space position, normal (face normal for flat shading, trimesh
// vertex normal for smooth) and UV per vertex; everything else is derived per fragment.
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;

uniform mat4 u_model;           // M(t)
uniform mat4 u_view;
uniform mat4 u_proj;

out vec3 v_local;
out vec3 v_normal_local;
out vec2 v_uv;
out vec3 v_world;
out vec4 v_view;
out vec4 v_view_open;           // the point's view position at shutter open / close
out vec4 v_view_close;

void main() {
    vec4 world = u_model * vec4(in_position, 1.0);
    v_local = in_position;
    v_normal_local = in_normal;
    v_uv = in_uv;
    v_world = world.xyz;
    v_view = u_view * world;
    v_view_open = view_open(in_position);
    v_view_close = view_close(in_position);
    gl_Position = u_proj * v_view;
}
