#version 330 core
// Which objects have edge pixels (mask_edge_probe: their id there) in each u_tile x u_tile tile, as a bitmask of
// (object id mod 32), in three steps: STAGE 0 over u_tile texels along x (full size ->
// strip), STAGE 1 over u_tile strip texels along y (strip -> tiles), STAGE 2 the 3x3 tiles
// around each tile (so a point's tile answers for everything within a tile of it). The
// range check (raymask_range.frag) skips searches whose points see no tile with an edge
// of the pixel's own object: a superset of the ids, so the skip is exact.
uniform int u_tile;
out uint out_bits;
#if STAGE == 0
uniform sampler2D u_probe;      // .y: the object id at an edge pixel, 0 elsewhere
#else
uniform usampler2D u_source;
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint bits = 0u;
#if STAGE == 0
    ivec2 size = textureSize(u_probe, 0);
    int x0 = p.x * u_tile, x1 = min(x0 + u_tile, size.x);
    for (int x = x0; x < x1; ++x) {
        uint id = uint(texelFetch(u_probe, ivec2(x, p.y), 0).y);
        bits |= id != 0u ? 1u << (id % 32u) : 0u;
    }
#elif STAGE == 1
    ivec2 size = textureSize(u_source, 0);
    int y0 = p.y * u_tile, y1 = min(y0 + u_tile, size.y);
    for (int y = y0; y < y1; ++y) bits |= texelFetch(u_source, ivec2(p.x, y), 0).x;
#else
    ivec2 size = textureSize(u_source, 0);
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
