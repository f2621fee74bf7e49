#version 330 core
// The longest displacement |D| (px over the exposure) in each u_tile x u_tile tile of the
// G-buffer's velocity, for the host's tile lists (viewer/render/tile_lists.py). length()
// is the one the ray mask passes compare with hybrid.min_speed, so a tile holds a moving
// pixel exactly when its value reaches that speed. Texels past the screen are skipped.
uniform sampler2D u_velocity;
uniform int u_tile;
out float out_max;

void main() {
    ivec2 size = textureSize(u_velocity, 0);
    ivec2 start = ivec2(gl_FragCoord.xy) * u_tile;
    ivec2 stop = min(start + u_tile, size);
    float m = 0.0;
    for (int y = start.y; y < stop.y; ++y) {
        for (int x = start.x; x < stop.x; ++x) {
            m = max(m, length(texelFetch(u_velocity, ivec2(x, y), 0).xy));
        }
    }
    out_max = m;
}
