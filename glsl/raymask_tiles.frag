#version 330 core
// Per-tile summary of a ray-mask buffer, so later passes can skip pixels with nothing in
// reach (tiles are k x k, k the blur limit: anything within k px lies in the 3x3 tiles
// around a pixel's own). MODE 0, over mask_edge: (largest half relative displacement of an
// edge pixel, 1 if the tile has an edge). MODE 1, over ray_mask: (0, 1 if anything is
// masked). Texels past the screen's edge (a partial last tile) are skipped.
uniform usampler2D u_mask;
uniform sampler2D u_relative;
uniform int u_tile;
out vec2 out_summary;

void main() {
    ivec2 size = textureSize(u_mask, 0);
    ivec2 start = ivec2(gl_FragCoord.xy) * u_tile;
    ivec2 stop = min(start + u_tile, size);
    vec2 s = vec2(0.0);
    for (int y = start.y; y < stop.y; ++y) {
        for (int x = start.x; x < stop.x; ++x) {
            if (texelFetch(u_mask, ivec2(x, y), 0).x == 0u) continue;
#if MODE == 0
            s = max(s, vec2(0.5 * length(texelFetch(u_relative, ivec2(x, y), 0).xy), 1.0));
#else
            s.y = 1.0;
#endif
        }
    }
    out_summary = s;
}
