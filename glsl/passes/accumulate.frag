#version 330 core
// Adds weight * source to the target (additive blending): the reference's running mean.
uniform sampler2D u_src;
uniform float u_weight;
out vec4 out_color;
void main() {
    out_color = texelFetch(u_src, ivec2(gl_FragCoord.xy), 0) * u_weight;
}
