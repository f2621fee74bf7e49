#version 330 core
// Clears a revealed layer's targets to "nothing revealed": alpha 0, the background's depth,
// id 0 and no motion (integer targets cannot be cleared with a float clear colour).
layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_depth;
layout(location = 2) out uint out_id;
layout(location = 3) out vec2 out_velocity;

void main() {
    out_color = vec4(0.0);
    out_depth = BACKGROUND_DEPTH;
    out_id = 0u;
    out_velocity = vec2(0.0);
}
