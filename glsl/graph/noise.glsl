// Deterministic per-pixel noise. Every jitter in the filters comes from here, keyed by the
// pixel and u_seed, so the same seed gives byte-identical images.
uniform uint u_seed;

// Jimenez 2014's interleaved gradient noise in [0, 1); `offset` decorrelates several draws.
float ign(vec2 pixel, float offset) {
    vec2 p = pixel + offset * 5.588238 + float(u_seed % 1024u) * 7.13;
    return fract(52.9829189 * fract(dot(p, vec2(0.06711056, 0.00583715))));
}

// A 32-bit integer hash (lowbias32) of the pixel, the seed and a stream number, in [0, 1).
float hash01(ivec2 pixel, uint stream) {
    uint x = uint(pixel.x) * 73856093u ^ uint(pixel.y) * 19349663u ^ (u_seed + stream * 83492791u);
    x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
    return float(x >> 8) * (1.0 / 16777216.0);
}
