#version 330 core
// Which objects have edge pixels in each u_tile x u_tile tile, as a bitmask of (object id
// mod 32), and the largest reach (half the relative displacement) of an edge there, from
// mask_edge_probe (its (reach, id) at edge pixels, 0 elsewhere), in three steps: STAGE 0
// over u_tile texels along x (full size -> strip), STAGE 1 over u_tile strip texels along
// y (strip -> tiles), STAGE 2 the 3x3 tiles around each tile (so a point's tile answers
// for everything within a tile of it), STAGES 3 and 4 the ids of the tiles within
// u_radius (so a pixel's tile answers for everything the range check can reach from it).
// Output (bits, floatBitsToUint(reach)): reaches are
// >= 0, whose float bits order as the floats do, so max() of the bits is their max.
// The range check (raymask_range.frag) skips searches whose points see no tile with an
// edge of the pixel's own object, and bounds the others by the reaches they see: the ids
// are a superset and the reaches an upper bound, so both are exact.
uniform int u_tile;
out uvec2 out_near;
#if STAGE == 0
uniform sampler2D u_probe;
#else
uniform usampler2D u_source;
uniform int u_radius;
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uvec2 near = uvec2(0u);
#if STAGE == 0
    ivec2 size = textureSize(u_probe, 0);
    int x0 = p.x * u_tile, x1 = min(x0 + u_tile, size.x);
    for (int x = x0; x < x1; ++x) {
        vec2 e = texelFetch(u_probe, ivec2(x, p.y), 0).xy;
        uint id = uint(e.y);
        near.x |= id != 0u ? 1u << (id % 32u) : 0u;
        near.y = max(near.y, id != 0u ? floatBitsToUint(e.x) : 0u);
    }
#elif STAGE == 1
    ivec2 size = textureSize(u_source, 0);
    int y0 = p.y * u_tile, y1 = min(y0 + u_tile, size.y);
    for (int y = y0; y < y1; ++y) {
        uvec2 t = texelFetch(u_source, ivec2(p.x, y), 0).xy;
        near = uvec2(near.x | t.x, max(near.y, t.y));
    }
#elif STAGE == 2
    // The 3x3 tiles around.
    ivec2 size = textureSize(u_source, 0);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = p + ivec2(dx, dy);
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size))) {
                uvec2 t = texelFetch(u_source, q, 0).xy;
                near = uvec2(near.x | t.x, max(near.y, t.y));
            }
        }
    }
#else
    // STAGE 3 / 4: the tiles within u_radius along x, then along y (separable).
    ivec2 size = textureSize(u_source, 0);
    ivec2 axis = STAGE == 3 ? ivec2(1, 0) : ivec2(0, 1);
    for (int k = -u_radius; k <= u_radius; ++k) {
        ivec2 q = p + k * axis;
        if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size)))
            near.x |= texelFetch(u_source, q, 0).x;
    }
#endif
    out_near = near;
}
