#version 330 core
// Which u_tile x u_tile tiles of a uint mask hold a nonzero texel (1) or none (0), in two
// separable steps so the reads spread over many fragments: STAGE 0 over u_tile texels
// along x (full size -> strip), STAGE 1 over u_tile strip texels along y (strip -> tiles).
// Texels past the screen are skipped.
uniform usampler2D u_source;
uniform int u_tile;
out uint out_any;

void main() {
    ivec2 size = textureSize(u_source, 0);
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint any_set = 0u;
#if STAGE == 0
    int x0 = p.x * u_tile, x1 = min(x0 + u_tile, size.x);
    for (int x = x0; x < x1; ++x) any_set |= texelFetch(u_source, ivec2(x, p.y), 0).x;
#else
    int y0 = p.y * u_tile, y1 = min(y0 + u_tile, size.y);
    for (int y = y0; y < y1; ++y) any_set |= texelFetch(u_source, ivec2(p.x, y), 0).x;
#endif
    out_any = any_set != 0u ? 1u : 0u;
}
