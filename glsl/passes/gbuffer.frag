#version 330 core
#include "passes/shading.glsl"
#include "passes/motion.glsl"
#include "passes/gbuffer_outputs.glsl"

in vec3 v_local;
in vec3 v_normal_local;
in vec2 v_uv;
in vec3 v_world;
in vec4 v_view;
in vec4 v_view_open;
in vec4 v_view_close;
#if SEGMENTS > 1
#include "passes/path.glsl"
in vec4 v_view_path[SEGMENTS];
#endif

uniform mat3 u_normal_matrix;   // inverse transpose of M(t)'s upper 3x3
uniform uint u_object_id;
#ifdef RANK_LOCATION
uniform uint u_rank;
#endif

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
#ifdef RANK_LOCATION
    out_rank = u_rank;
#endif
#if SEGMENTS > 1
    // The path's points as offsets from this point's own window position now.
    vec2 o[SEGMENTS];
    for (int j = 0; j < SEGMENTS; ++j)
        o[j] = saturate_displacement(to_window(clip_to_near(v_view_path[j], v_view))
                                     - to_window(v_view));
    out_path0 = vec4(o[0], o[1]);
#if SEGMENTS == 4
    out_path1 = vec4(o[2], o[3]);
#endif
#endif
}
