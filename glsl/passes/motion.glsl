// Screen-space displacement over the exposure (world/conventions.py): the window position
// of a surface point at shutter close minus at shutter open, in pixels, GL axes (y up).

// V(t_open) M(t_open) and V(t_close) M(t_close), t_open/close = t -/+ shutter/2: the camera's
// view times the object's model matrix, combined on the host (one product per point, not
// two: the reveal's shading computes these per fragment).
uniform mat4 u_modelview_open;
uniform mat4 u_modelview_close;
uniform vec2 u_focal;           // the projection's (P[0][0], P[1][1]); its frustum is
                                // symmetric, so clip.xy = u_focal * xy and clip.w = -z
uniform vec2 u_viewport;        // framebuffer size in pixels
uniform float u_near;

vec2 to_window(vec4 view_pos) {
    return (u_focal * view_pos.xy / -view_pos.z * 0.5 + 0.5) * u_viewport;
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

// View-space positions at shutter open and close. They are affine in the mesh-space point,
// so a vertex shader may compute them per vertex and let (perspective-correct)
// interpolation deliver the exact per-fragment values.
vec4 view_open(vec3 p_local) { return u_modelview_open * vec4(p_local, 1.0); }
vec4 view_close(vec3 p_local) { return u_modelview_close * vec4(p_local, 1.0); }

// Displacements past any blur limit are cut to DISPLACEMENT_LIMIT px along the same
// direction: every reader takes length(D), whose square overflows float32 from ~1.8e19
// px (an object at ~1e20 m/s): length() then reads inf and the blur limit's scaling turns
// D into 0 (no blur at all). An infinite component (matrices past float32) is first
// taken as the largest finite value.
const float DISPLACEMENT_LIMIT = 1e9;
vec2 saturate_displacement(vec2 d) {
    d = clamp(d, vec2(-3.0e38), vec2(3.0e38));
    float m = max(abs(d.x), abs(d.y));
    return m > DISPLACEMENT_LIMIT ? d * (DISPLACEMENT_LIMIT / m) : d;
}

vec2 displacement_between(vec4 q_open, vec4 q_close, vec4 view_now) {
    return saturate_displacement(to_window(clip_to_near(q_close, view_now))
                                 - to_window(clip_to_near(q_open, view_now)));
}

vec2 exposure_displacement(vec3 p_local, vec4 view_now) {
    return displacement_between(view_open(p_local), view_close(p_local), view_now);
}
