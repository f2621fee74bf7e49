#version 330 core
// UE4-style flatten: the half vector v = D/2 (the filter blurs from -v to +v), its length
// clamped to the shared blur limit, packed with the linear depth: (v.x, v.y, depth, |v|).
uniform sampler2D u_velocity;   // full displacement D over the exposure, px, y up
uniform sampler2D u_depth;      // positive linear view depth, m
uniform float u_max_px;         // blur limit per side, px
out vec4 out_flat;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec2 v = 0.5 * texelFetch(u_velocity, p, 0).xy;
    float len = length(v);
    if (len > u_max_px) {
        v *= u_max_px / len;
        len = u_max_px;
    }
    out_flat = vec4(v, texelFetch(u_depth, p, 0).r, len);
}
