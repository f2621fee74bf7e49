#version 330 core
// Fills the G-buffer where nothing is hit (drawn first, without depth test).
uniform vec3 u_background;
layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_depth;
layout(location = 2) out vec4 out_normal;
layout(location = 3) out uint out_id;
layout(location = 4) out vec2 out_velocity;
void main() {
    out_color = vec4(u_background, 1.0);
    out_depth = BACKGROUND_DEPTH;
    out_normal = vec4(0.0);
    out_id = 0u;
    out_velocity = vec2(0.0);
}
