#version 330 core
// Per channel, the largest of the 3x3 texels around this one (texels past the edge skipped).
uniform sampler2D u_source;
out vec2 out_max;

void main() {
    ivec2 t = ivec2(gl_FragCoord.xy);
    ivec2 n = textureSize(u_source, 0);
    vec2 m = vec2(0.0);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 p = t + ivec2(dx, dy);
            if (all(greaterThanEqual(p, ivec2(0))) && all(lessThan(p, n)))
                m = max(m, texelFetch(u_source, p, 0).xy);
        }
    }
    out_max = m;
}
