#version 330 core
// Per-tile summary of a ray-mask buffer, so later passes can skip pixels with nothing in
// reach (tiles are k x k, k the blur limit: anything within k px lies in the 3x3 tiles
// around a pixel's own). Two separable steps, so the work spreads over many fragments
// (one fragment per tile would run k*k texel reads serially in one raster bin):
// STAGE 0, over u_tile texels along x (full size -> ceil(W/k) x H strip), of the mask:
//   (0, 1 if anything is masked);
// STAGE 1, over u_tile strip texels along y (strip -> tiles): the largest per channel.
// Texels past the screen's edge (a partial last tile) are skipped. With MOTION_TILES a
// strip texel whose pixels lie in no moving 16 x 16 tile (viewer/render/tile_lists.py)
// is 0 without reading them: the masks are only ever set on moving pixels.
uniform int u_tile;
out vec2 out_summary;
#if STAGE == 0
uniform usampler2D u_mask;
#if MOTION_TILES
uniform sampler2D u_motion_tiles;
uniform int u_fine;
uniform float u_min_speed;

bool any_moving(int x0, int x1, int y) {
    for (int fx = x0 / u_fine; fx <= (x1 - 1) / u_fine; ++fx) {
        if (texelFetch(u_motion_tiles, ivec2(fx, y / u_fine), 0).x >= u_min_speed) return true;
    }
    return false;
}
#endif

void main() {
    ivec2 size = textureSize(u_mask, 0);
    int y = int(gl_FragCoord.y);
    int x0 = int(gl_FragCoord.x) * u_tile;
    int x1 = min(x0 + u_tile, size.x);
    vec2 s = vec2(0.0);
#if MOTION_TILES
    if (!any_moving(x0, x1, y)) { out_summary = s; return; }
#endif
    for (int x = x0; x < x1; ++x) {
        if (texelFetch(u_mask, ivec2(x, y), 0).x != 0u) s.y = 1.0;
    }
    out_summary = s;
}
#else
uniform sampler2D u_strip;

void main() {
    ivec2 size = textureSize(u_strip, 0);
    int x = int(gl_FragCoord.x);
    int y0 = int(gl_FragCoord.y) * u_tile;
    int y1 = min(y0 + u_tile, size.y);
    vec2 s = vec2(0.0);
    for (int y = y0; y < y1; ++y) s = max(s, texelFetch(u_strip, ivec2(x, y), 0).xy);
    out_summary = s;
}
#endif
