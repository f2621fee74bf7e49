#version 330 core
// Ray mask, step 2: the edge test. Survivors of the displacement test are kept where a
// Sobel kernel on log depth or on the world normal exceeds its threshold: the moving
// silhouettes (and creases next to them). The kernel is divided by 4, so a one-pixel step
// of size s reads as s.
// Second target, for the range check's inner loop (one fetch per probe): (half the
// relative displacement, the object id) at an edge pixel, (0, 0) elsewhere (id 0 is the
// sky, never a searching pixel's own).
uniform usampler2D u_displacement_mask;
uniform usampler2D u_id;
uniform sampler2D u_relative;
uniform sampler2D u_depth;
uniform sampler2D u_normal;
uniform float u_edge_depth;
uniform float u_edge_normal;
layout(location = 0) out uint out_edge;
layout(location = 1) out vec2 out_probe;

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    out_edge = 0u;
    out_probe = vec2(0.0);
    if (texelFetch(u_displacement_mask, x, 0).x == 0u) return;
    ivec2 size = textureSize(u_depth, 0);
    vec2 gz = vec2(0.0);
    vec3 gnx = vec3(0.0), gny = vec3(0.0);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            if (dx == 0 && dy == 0) continue;
            ivec2 p = clamp(x + ivec2(dx, dy), ivec2(0), size - 1);
            // Sobel weights: 2 on the axis, 1 on the diagonals; sign by side.
            vec2 w = vec2(float(dx) * (dy == 0 ? 2.0 : 1.0), float(dy) * (dx == 0 ? 2.0 : 1.0));
            float z = log(max(texelFetch(u_depth, p, 0).x, 1e-6));
            vec3 n = texelFetch(u_normal, p, 0).xyz;
            gz += w * z;
            gnx += w.x * n;
            gny += w.y * n;
        }
    }
    float g_depth = 0.25 * length(gz);
    float g_normal = 0.25 * sqrt(dot(gnx, gnx) + dot(gny, gny));
    if (g_depth > u_edge_depth || g_normal > u_edge_normal) {
        out_edge = 1u;
        out_probe = vec2(0.5 * length(texelFetch(u_relative, x, 0).xy),
                         float(texelFetch(u_id, x, 0).x));
    }
}
