// The layers the hybrid composites resolve (viewer/render/modes/hybrid/composite.py).
// front: the G-buffer's hybrid_front, (D.xy, depth, object id), D the displacement over the
//     exposure, read through front_motion() which clamps it to the blur limit u_max_disp
//     (|D| <= 2k);
// back: written by reveal_shade where a ray was cast, (D.xy, depth, 1 + the revealed
//     object's id), and cleared to 0 elsewhere: there it reads the front with w = 0,
//     "nothing revealed here", so a back-layer walk that leaves the mask reads the
//     visible surface. D clamped on read, as the front's.
uniform sampler2D u_front_color;
uniform sampler2D u_front;
uniform sampler2D u_back_color;
uniform sampler2D u_back;

uniform float u_max_disp;

vec4 clamp_motion(vec4 f) {
    float l = length(f.xy);
    return l > u_max_disp ? vec4(f.xy * (u_max_disp / l), f.zw) : f;
}

vec4 front_motion(ivec2 p) { return clamp_motion(texelFetch(u_front, p, 0)); }
vec3 front_colour(ivec2 p) { return texelFetch(u_front_color, p, 0).rgb; }

vec4 back_motion(ivec2 p) {
    vec4 b = texelFetch(u_back, p, 0);
    return b.w > 0.5 ? clamp_motion(b) : vec4(front_motion(p).xyz, 0.0);
}
vec3 back_colour(ivec2 p) {
    vec4 c = texelFetch(u_back_color, p, 0);
    return c.a > 0.5 ? c.rgb : front_colour(p);
}
