#version 330 core
// McGuire 2012 velocity setup (docs/algorithms.md 1.1): the half vector v = D/2 of the
// G-buffer's full displacement D, its magnitude clamped to [0.5, k] px. Exactly zero stays
// zero; any motion at all gets a PSF radius of at least half a pixel.
uniform sampler2D u_displacement;
uniform float u_max_radius;    // k, the tile size
out vec2 out_v;

void main() {
    vec2 q = 0.5 * texelFetch(u_displacement, ivec2(gl_FragCoord.xy), 0).xy;
    // Normalise by the largest component first: |q| of a tiny q would underflow to 0.
    float m = max(abs(q.x), abs(q.y));
    if (m == 0.0) {
        out_v = vec2(0.0);
        return;
    }
    vec2 u = q / m;
    float lu = length(u);
    out_v = (u / lu) * clamp(m * lu, 0.5, u_max_radius);
}
