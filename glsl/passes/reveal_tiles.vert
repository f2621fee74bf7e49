#version 330 core
// Tile quads (glsl/passes/tiles.vert) that also carry where each pixel's hit record lies in the
// block-packed record texture (viewer/render/modes/hybrid/reveal.py layer_hits): the record
// coordinate is an affine function of the window position, so its interpolated value at
// a fragment is that fragment's record (floor it).
in vec2 in_corner;
in vec2 in_record;
uniform vec2 u_viewport;
noperspective out vec2 v_record;
void main() {
    gl_Position = vec4(in_corner / u_viewport * 2.0 - 1.0, 0.0, 1.0);
    v_record = in_record;
}
