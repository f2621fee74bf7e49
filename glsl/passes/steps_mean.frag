#version 330 core
// The sub-exposure steps' last draw (viewer/render/steps.py): with the blend factors
// (ONE, SRC_ALPHA) on colour, the target (the last sub-frame's image) becomes
// weight * source + weight * target, the mean of the n sub-frames when the source holds
// the sum of the others; the target's alpha is kept (blend factors ZERO, ONE).
uniform sampler2D u_src;
uniform float u_weight;
out vec4 out_color;
void main() {
    out_color = vec4(texelFetch(u_src, ivec2(gl_FragCoord.xy), 0).rgb * u_weight, u_weight);
}
