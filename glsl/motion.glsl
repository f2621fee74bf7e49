// Screen-space displacement over the exposure (viewer/conventions.py): the window position
// of a surface point at shutter close minus at shutter open, in pixels, GL axes (y up).

uniform mat4 u_model_open;      // M(t - shutter/2)
uniform mat4 u_model_close;     // M(t + shutter/2)
uniform mat4 u_view_open;       // camera view at shutter open / close
uniform mat4 u_view_close;
uniform mat4 u_proj;
uniform vec2 u_viewport;        // framebuffer size in pixels
uniform float u_near;

vec2 to_window(vec4 view_pos) {
    vec4 clip = u_proj * view_pos;
    return (clip.xy / clip.w * 0.5 + 0.5) * u_viewport;
}

// A point behind the near plane at one end of the exposure has no screen position there:
// the motion segment (in view space, linearised) is cut where it crosses the near plane,
// so the displacement stays finite and points the right way.
vec4 clip_to_near(vec4 q, vec4 q_now) {
    float d = -q.z, d_now = -q_now.z;
    if (d >= u_near) return q;
    float s = (d_now - u_near) / max(d_now - d, 1e-12);
    return mix(q_now, q, clamp(s, 0.0, 1.0) * 0.999);
}

vec2 exposure_displacement(vec3 p_local, vec4 view_now) {
    vec4 q0 = clip_to_near(u_view_open * (u_model_open * vec4(p_local, 1.0)), view_now);
    vec4 q1 = clip_to_near(u_view_close * (u_model_close * vec4(p_local, 1.0)), view_now);
    return to_window(q1) - to_window(q0);
}
