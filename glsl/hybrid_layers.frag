#version 330 core
// The two (or three) layers the hybrid composite resolves, packed for its inner loop:
// front = the raster G-buffer, back = the revealed layer where a ray was cast and the
// raster elsewhere (so a back-layer walk that leaves the mask reads the visible
// background), back2 = the second revealed layer where traced, else back. Each motion
// texel is (D.x, D.y, depth, revealed): the displacement over the exposure clamped to the
// blur limit (|D| <= 2k), the linear depth, and 1 + the revealed object's id where the
// layer's own data is revealed (0 elsewhere); the front texel holds the object id there
// instead (ids are exact as floats below 2^24).
uniform sampler2D u_color;
uniform sampler2D u_depth;
uniform usampler2D u_id;
uniform sampler2D u_velocity;
uniform sampler2D u_rev_color;
uniform sampler2D u_rev_depth;
uniform usampler2D u_rev_id;
uniform sampler2D u_rev_velocity;
uniform sampler2D u_rev2_color;
uniform sampler2D u_rev2_depth;
uniform usampler2D u_rev2_id;
uniform sampler2D u_rev2_velocity;
uniform float u_max_disp;
layout(location = 0) out vec4 out_front;
layout(location = 1) out vec4 out_back;
layout(location = 2) out vec4 out_back_color;
layout(location = 3) out vec4 out_back2;
layout(location = 4) out vec4 out_back2_color;

vec2 clamp_length(vec2 d) {
    float l = length(d);
    return l > u_max_disp ? d * (u_max_disp / l) : d;
}

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    vec4 c = texelFetch(u_color, x, 0);
    vec2 d = clamp_length(texelFetch(u_velocity, x, 0).xy);
    float z = texelFetch(u_depth, x, 0).x;
    out_front = vec4(d, z, float(texelFetch(u_id, x, 0).x));
    out_back = vec4(d, z, 0.0);
    out_back_color = vec4(c.rgb, 0.0);
    vec4 rc = texelFetch(u_rev_color, x, 0);
    if (rc.a > 0.5) {
        out_back = vec4(clamp_length(texelFetch(u_rev_velocity, x, 0).xy),
                        texelFetch(u_rev_depth, x, 0).x, 1.0 + float(texelFetch(u_rev_id, x, 0).x));
        out_back_color = vec4(rc.rgb, 1.0);
    }
    out_back2 = out_back;
    out_back2_color = out_back_color;
    vec4 rc2 = texelFetch(u_rev2_color, x, 0);
    if (rc2.a > 0.5) {
        out_back2 = vec4(clamp_length(texelFetch(u_rev2_velocity, x, 0).xy),
                         texelFetch(u_rev2_depth, x, 0).x, 1.0 + float(texelFetch(u_rev2_id, x, 0).x));
        out_back2_color = vec4(rc2.rgb, 1.0);
    }
}
