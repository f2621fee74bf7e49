#version 330 core
// A naive gather along each pixel's own motion (an example of a user blur pass,
// docs/api.md): the mean of TAPS colours spaced evenly along the pixel's half
// displacement v = D/2 on both sides, |v| clamped to the blur limit k. No depth test and
// no neighbourhood: a moving object smears, but the background beside it never takes the
// object's colour (no outer blur), which the scores per region show.
uniform sampler2D u_color;       // linear RGB of the sharp frame
uniform sampler2D u_velocity;    // displacement over the exposure, pixels, x right, y up
uniform int u_tile;              // k: the blur limit in pixels
out vec4 out_color;              // the blurred linear colour

const int TAPS = 9;

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_color, 0);
    vec2 v = 0.5 * texelFetch(u_velocity, x, 0).xy;
    float len = length(v);
    if (len > float(u_tile)) v *= float(u_tile) / len;
    vec3 sum = vec3(0.0);
    for (int i = 0; i < TAPS; ++i) {
        float t = -1.0 + 2.0 * float(i) / float(TAPS - 1);
        ivec2 y = clamp(ivec2(floor(vec2(x) + 0.5 + t * v)), ivec2(0), size - 1);
        sum += texelFetch(u_color, y, 0).rgb;
    }
    out_color = vec4(sum / float(TAPS), 1.0);
}
