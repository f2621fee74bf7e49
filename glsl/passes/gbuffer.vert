#version 330 core
#include "passes/motion.glsl"
// G-buffer geometry: mesh-space position, normal (face normal for flat shading, trimesh
// vertex normal for smooth) and UV per vertex; everything else is derived per fragment.
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
// The point at shutter open and close (and the path's quarter points): a rigid object's
// buffer gives its one position for each (its model matrices move it), a skinned one's
// the posed positions (GpuScene.vao).
in vec3 in_position_open;
in vec3 in_position_close;
#if SEGMENTS == 4
in vec3 in_path1;
in vec3 in_path3;
#endif

// Composed on the host in float64 (GpuScene.object_matrices): in float32 a scene far from
// the origin would lose its detail to the world translation before V subtracts it again.
uniform mat4 u_model_eye;       // T(-eye(t)) M(t): world position relative to the eye
uniform mat4 u_modelview;       // V(t) M(t)
uniform mat4 u_proj;

out vec3 v_local;
out vec3 v_normal_local;
out vec2 v_uv;
out vec3 v_world;               // relative to the eye
out vec4 v_view;
out vec4 v_view_open;           // the point's view position at shutter open / close
out vec4 v_view_close;
#if SEGMENTS > 1
#include "passes/path.glsl"
// V(t_k) M(t_k) for k = 0..K (GpuScene.path_matrices); the points' view positions, the
// middle one (the frame time: v_view) left out.
uniform mat4 u_modelview_path[PATH_POINTS];
out vec4 v_view_path[SEGMENTS];
#endif

void main() {
    v_local = in_position;
    v_normal_local = in_normal;
    v_uv = in_uv;
    v_world = (u_model_eye * vec4(in_position, 1.0)).xyz;
    v_view = u_modelview * vec4(in_position, 1.0);
    v_view_open = view_open(in_position_open);
    v_view_close = view_close(in_position_close);
#if SEGMENTS == 2
    v_view_path[0] = u_modelview_path[0] * vec4(in_position_open, 1.0);
    v_view_path[1] = u_modelview_path[2] * vec4(in_position_close, 1.0);
#elif SEGMENTS == 4
    v_view_path[0] = u_modelview_path[0] * vec4(in_position_open, 1.0);
    v_view_path[1] = u_modelview_path[1] * vec4(in_path1, 1.0);
    v_view_path[2] = u_modelview_path[3] * vec4(in_path3, 1.0);
    v_view_path[3] = u_modelview_path[4] * vec4(in_position_close, 1.0);
#endif
    gl_Position = u_proj * v_view;
}
