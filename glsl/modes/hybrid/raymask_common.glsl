// Shared by the ray-mask passes (viewer/render/modes/hybrid/mask.py). Positions are GL window pixels
// (row 0 at the bottom), displacements the G-buffer's full motion over the exposure.

// The pixel whose centre is nearest to (centre of x) + offset, clamped to the screen: a
// probe past the border reads the border pixel (off-screen content is not "behind").
ivec2 probe(ivec2 x, vec2 offset, ivec2 size) {
    return clamp(ivec2(floor(vec2(x) + 0.5 + offset)), ivec2(0), size - 1);
}
