#version 330 core
// The longest displacement |D| (px over the exposure) in each u_tile x u_tile tile of the
// G-buffer's hybrid_front (.xy: D), for the host's tile lists (viewer/render/tile_lists.py), in two
// separable steps so the reads spread over many fragments: STAGE 0 over u_tile texels
// along x (full size -> strip), STAGE 1 over u_tile strip texels along y. length() is the
// one the ray mask passes compare with hybrid.min_speed, so a tile holds a moving pixel
// exactly when its value reaches that speed. Texels past the screen are skipped.
uniform sampler2D u_source;
uniform int u_tile;
out float out_max;

void main() {
    ivec2 size = textureSize(u_source, 0);
    ivec2 p = ivec2(gl_FragCoord.xy);
#if STAGE == 0
    int x0 = p.x * u_tile, x1 = min(x0 + u_tile, size.x);
    float m = 0.0;
    for (int x = x0; x < x1; ++x) m = max(m, length(texelFetch(u_source, ivec2(x, p.y), 0).xy));
#else
    int y0 = p.y * u_tile, y1 = min(y0 + u_tile, size.y);
    float m = 0.0;
    for (int y = y0; y < y1; ++y) m = max(m, texelFetch(u_source, ivec2(p.x, y), 0).x);
#endif
    out_max = m;
}
