#version 330 core
// NeighborMax (McGuire et al. 2012): the TileMax vector of largest magnitude over the 3x3
// tiles around this one, tiles outside the grid skipped. The centre is taken first and
// wins ties, so a neighbourhood of equal speeds keeps its own direction.
// DIAGONAL_TOWARD 1 (Guertin et al. 2014): a diagonal neighbour at offset o counts only
// where its vector points toward this tile (dot(v, -o) > 0); its blur cannot reach this
// tile otherwise, and taking it would smear a corner across the tile.
uniform sampler2D u_tiles;
out vec2 out_max;

void main() {
    ivec2 t = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_tiles, 0);
    vec2 best = texelFetch(u_tiles, t, 0).xy;
    float best2 = dot(best, best);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 p = t + ivec2(dx, dy);
            if (p.x < 0 || p.y < 0 || p.x >= size.x || p.y >= size.y) continue;
            vec2 v = texelFetch(u_tiles, p, 0).xy;
#if DIAGONAL_TOWARD
            if (dx != 0 && dy != 0 && dot(v, -vec2(dx, dy)) <= 0.0) continue;
#endif
            float m2 = dot(v, v);
            if (m2 > best2) { best = v; best2 = m2; }
        }
    }
    out_max = best;
}
