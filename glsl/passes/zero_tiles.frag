#version 330 core
// Every target of the framebuffer back to 0, drawn over the tiles a tiled pass wrote last
// frame and does not draw again (viewer/render/passes/tile_runs.py clear_outside; a scissored
// clear would cover their whole box). OUTk: OUT_FLOAT for a float target at location k,
// OUT_INT for an integer one, 0 past the last (up to 4 targets; codes from tile_runs.py).
#if OUT0 == OUT_FLOAT
layout(location = 0) out vec4 o0;
#elif OUT0 == OUT_INT
layout(location = 0) out uvec4 o0;
#endif
#if OUT1 == OUT_FLOAT
layout(location = 1) out vec4 o1;
#elif OUT1 == OUT_INT
layout(location = 1) out uvec4 o1;
#endif
#if OUT2 == OUT_FLOAT
layout(location = 2) out vec4 o2;
#elif OUT2 == OUT_INT
layout(location = 2) out uvec4 o2;
#endif
#if OUT3 == OUT_FLOAT
layout(location = 3) out vec4 o3;
#elif OUT3 == OUT_INT
layout(location = 3) out uvec4 o3;
#endif

void main() {
#if OUT0 == OUT_FLOAT
    o0 = vec4(0.0);
#elif OUT0 == OUT_INT
    o0 = uvec4(0u);
#endif
#if OUT1 == OUT_FLOAT
    o1 = vec4(0.0);
#elif OUT1 == OUT_INT
    o1 = uvec4(0u);
#endif
#if OUT2 == OUT_FLOAT
    o2 = vec4(0.0);
#elif OUT2 == OUT_INT
    o2 = uvec4(0u);
#endif
#if OUT3 == OUT_FLOAT
    o3 = vec4(0.0);
#elif OUT3 == OUT_INT
    o3 = uvec4(0u);
#endif
}
