#version 330 core
// A revealed layer's targets (reveal_shade.frag's) back to "nothing revealed": alpha 0,
// the background's depth, id 0, no motion, packed texels 0 (integer targets cannot be
// cleared with a float clear colour, and a scissored clear would cover a whole box).
layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_depth;
layout(location = 2) out uint out_id;
layout(location = 3) out vec2 out_velocity;
layout(location = 4) out vec4 out_packed;
layout(location = 5) out vec4 out_packed_color;

void main() {
    out_color = vec4(0.0);
    out_depth = BACKGROUND_DEPTH;
    out_id = 0u;
    out_velocity = vec2(0.0);
    out_packed = vec4(0.0);
    out_packed_color = vec4(0.0);
}
