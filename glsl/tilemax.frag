#version 330 core
// One separable TileMax step (ALGORITHMS.md 1.2): the velocity of largest magnitude over
// u_tile texels of the source along u_axis, starting at this texel's tile. Texels past the
// source's edge (a partial last tile) are skipped. Ties keep the first texel in scan order.
uniform sampler2D u_velocity;
uniform int u_tile;
uniform ivec2 u_axis;          // (1, 0): k x 1, full width -> strip; (0, 1): 1 x k
out vec2 out_max;

void main() {
    ivec2 t = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_velocity, 0);
    // Along the axis the texel index is a tile index; across it, the same row/column.
    ivec2 start = t * (ivec2(1) - u_axis) + t * u_axis * u_tile;
    vec2 best = vec2(0.0);
    float best2 = -1.0;
    for (int i = 0; i < u_tile; ++i) {
        ivec2 p = start + u_axis * i;
        if (p.x >= size.x || p.y >= size.y) break;
        vec2 v = texelFetch(u_velocity, p, 0).xy;
        float m2 = dot(v, v);
        if (m2 > best2) { best = v; best2 = m2; }
    }
    out_max = best;
}
