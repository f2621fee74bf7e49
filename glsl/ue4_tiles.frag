#version 330 core
// Per tile, the velocities of least and greatest length: (vmin.xy, vmax.xy), px.
// Pixels of a border tile that fall outside the screen take no part. Scan order (rows
// upward, then columns rightward) with strict compares settles ties, as the tests expect.
uniform sampler2D u_flat;       // (v.x, v.y, depth, |v|)
uniform int u_tile;
out vec4 out_tiles;

void main() {
    ivec2 size = textureSize(u_flat, 0);
    ivec2 base = ivec2(gl_FragCoord.xy) * u_tile;
    ivec2 end = min(base + u_tile, size);
    vec2 vmin = vec2(0.0), vmax = vec2(0.0);
    float lmin = 3.0e38, lmax = 0.0;      // any velocity replaces the initial min
    for (int y = base.y; y < end.y; ++y) {
        for (int x = base.x; x < end.x; ++x) {
            vec4 f = texelFetch(u_flat, ivec2(x, y), 0);
            if (f.w < lmin) { lmin = f.w; vmin = f.xy; }
            if (f.w > lmax) { lmax = f.w; vmax = f.xy; }
        }
    }
    out_tiles = vec4(vmin, vmax);
}
