#version 330 core
// The revealed layer, shaded exactly as the raster G-buffer shades (gbuffer.frag): the same
// shade() with the same GpuScene uniforms, the object's M(t) for position and normal, and
// its M at shutter open and close for the displacement, so the filter can blur it.
// u_miss draws the rays that left the scene: the background colour, as the G-buffer's
// background pass writes it. Alpha 1 marks "revealed" (cleared targets hold alpha 0).
// The last two targets hold the same packed for the composite (glsl/hybrid_layers.glsl):
// (D clamped to u_max_disp, depth, 1 + id) and (colour, 1).
#include "shading.glsl"
#include "motion.glsl"

in vec3 v_local;
in vec3 v_normal_local;
in vec2 v_uv;

uniform mat4 u_model;
uniform mat4 u_view;
uniform mat3 u_normal_matrix;
uniform vec3 u_eye;
uniform uint u_object_id;
uniform bool u_miss;
uniform vec3 u_background;
uniform float u_max_disp;

layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_depth;
layout(location = 2) out uint out_id;
layout(location = 3) out vec2 out_velocity;
layout(location = 4) out vec4 out_packed;
layout(location = 5) out vec4 out_packed_color;

void pack() {
    float l = length(out_velocity);
    vec2 d = l > u_max_disp ? out_velocity * (u_max_disp / l) : out_velocity;
    out_packed = vec4(d, out_depth, 1.0 + float(out_id));
    out_packed_color = out_color;
}

void main() {
    if (u_miss) {
        out_color = vec4(u_background, 1.0);
        out_depth = BACKGROUND_DEPTH;
        out_id = 0u;
        out_velocity = vec2(0.0);
        pack();
        return;
    }
    vec4 world = u_model * vec4(v_local, 1.0);
    vec4 view_now = u_view * world;
    vec3 n = normalize(u_normal_matrix * v_normal_local);
    if (dot(n, u_eye - world.xyz) < 0.0) n = -n;
    out_color = vec4(shade(world.xyz, n, v_local, v_uv, u_eye), 1.0);
    out_depth = -view_now.z;
    out_id = u_object_id;
    out_velocity = exposure_displacement(v_local, view_now);
    pack();
}
