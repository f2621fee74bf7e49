#version 330 core
// Tile quads for a pass drawn only where it has work (viewer/render/passes/tile_runs.py): each
// vertex is a tile corner in GL window pixels (row 0 at the bottom), cut at the screen edge.
// The fragment shader is the pass's own: it reads gl_FragCoord only, as under
// fullscreen.vert, so a pixel's result does not depend on how the pass was drawn.
in vec2 in_corner;
uniform vec2 u_viewport;
void main() {
    gl_Position = vec4(in_corner / u_viewport * 2.0 - 1.0, 0.0, 1.0);
}
