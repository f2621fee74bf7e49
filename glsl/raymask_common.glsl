// Shared by the ray-mask passes (viewer/render/raymask.py). Positions are GL window pixels
// (row 0 at the bottom), displacements the G-buffer's full motion over the exposure.

// The pixel whose centre is nearest to (centre of x) + offset, clamped to the screen: a
// probe past the border reads the border pixel (off-screen content is not "behind").
ivec2 probe(ivec2 x, vec2 offset, ivec2 size) {
    return clamp(ivec2(floor(vec2(x) + 0.5 + offset)), ivec2(0), size - 1);
}

// The largest of the 3x3 tile summaries around pixel x's tile, per channel.
vec2 neighbourhood(sampler2D tiles, ivec2 x, int tile) {
    ivec2 t = x / tile;
    ivec2 n = textureSize(tiles, 0);
    vec2 s = vec2(0.0);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 p = t + ivec2(dx, dy);
            if (all(greaterThanEqual(p, ivec2(0))) && all(lessThan(p, n))) {
                s = max(s, texelFetch(tiles, p, 0).xy);
            }
        }
    }
    return s;
}
