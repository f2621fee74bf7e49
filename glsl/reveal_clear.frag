#version 330 core
// A revealed layer's targets (reveal_shade.frag's) back to "nothing revealed": 0, drawn
// over last frame's tiles only (a scissored clear would cover their whole box).
layout(location = 0) out vec4 out_packed;
layout(location = 1) out vec4 out_packed_color;

void main() {
    out_packed = vec4(0.0);
    out_packed_color = vec4(0.0);
}
