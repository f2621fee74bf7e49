#version 330 core
// Which objects have edge pixels (mask_edge) in each u_tile x u_tile tile, as a bitmask of
// (object id mod 32), in three steps: STAGE 0 over u_tile texels along x (full size ->
// strip), STAGE 1 over u_tile strip texels along y (strip -> tiles), STAGE 2 the 3x3 tiles
// around each tile (so a point's tile answers for everything within a tile of it). The
// range check (raymask_range.frag) skips searches whose points see no tile with an edge
// of the pixel's own object: a superset of the ids, so the skip is exact.
uniform usampler2D u_source;
uniform int u_tile;
out uint out_bits;
#if STAGE == 0
uniform usampler2D u_id;
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_source, 0);
    uint bits = 0u;
#if STAGE == 0
    int x0 = p.x * u_tile, x1 = min(x0 + u_tile, size.x);
    for (int x = x0; x < x1; ++x) {
        if (texelFetch(u_source, ivec2(x, p.y), 0).x != 0u)
            bits |= 1u << (texelFetch(u_id, ivec2(x, p.y), 0).x % 32u);
    }
#elif STAGE == 1
    int y0 = p.y * u_tile, y1 = min(y0 + u_tile, size.y);
    for (int y = y0; y < y1; ++y) bits |= texelFetch(u_source, ivec2(p.x, y), 0).x;
#else
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = p + ivec2(dx, dy);
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size)))
                bits |= texelFetch(u_source, q, 0).x;
        }
    }
#endif
    out_bits = bits;
}
