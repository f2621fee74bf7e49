#version 330 core
// One point per revealed pixel, at its pixel centre, carrying the ray hit's mesh-space
// attributes (raytrace/reveal.py) to reveal_shade.frag. Pixels are image coordinates
// (column i, row j from the top), flipped here to GL's bottom-up window.
in vec2 in_pixel;
in vec3 in_local;
in vec3 in_normal;
in vec2 in_uv;

uniform vec2 u_viewport;

out vec3 v_local;
out vec3 v_normal_local;
out vec2 v_uv;

void main() {
    vec2 window = vec2(in_pixel.x + 0.5, u_viewport.y - in_pixel.y - 0.5);
    gl_Position = vec4(window / u_viewport * 2.0 - 1.0, 0.0, 1.0);
    gl_PointSize = 1.0;
    v_local = in_local;
    v_normal_local = in_normal;
    v_uv = in_uv;
}
