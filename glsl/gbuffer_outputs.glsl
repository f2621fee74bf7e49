// G-buffer render targets. GBUFFER_LAYOUT picks which are written (viewer/render/gbuffer.py
// keeps the same table): 0 = all, 1 = colour, depth and id (reference sub-frames that record
// visibility), 2 = colour only (plain reference sub-frames), 3 = all plus the hybrid
// composite's packed front layer (so no separate pass has to pack it).
#define GBUFFER_FULL (GBUFFER_LAYOUT == 0 || GBUFFER_LAYOUT == 3)
layout(location = 0) out vec4 out_color;         // linear, unclamped
#if GBUFFER_FULL
layout(location = 1) out float out_depth;        // linear view depth
layout(location = 2) out vec4 out_normal;        // world normal, facing the camera
layout(location = 3) out uint out_id;            // object id (0 = background)
layout(location = 4) out vec2 out_velocity;      // pixels over the exposure, GL axes
#elif GBUFFER_LAYOUT == 1
layout(location = 1) out float out_depth;
layout(location = 2) out uint out_id;
#endif
#if GBUFFER_LAYOUT == 3
// (D.xy clamped to |D| <= u_max_disp, depth, id): glsl/hybrid_layers.glsl's front layer.
layout(location = 5) out vec4 out_hybrid_front;
uniform float u_max_disp;
#endif

void write_gbuffer(vec3 color, float depth, vec3 normal, uint id, vec2 velocity) {
    out_color = vec4(color, 1.0);
#if GBUFFER_FULL
    out_depth = depth;
    out_normal = vec4(normal, 0.0);
    out_id = id;
    out_velocity = velocity;
#elif GBUFFER_LAYOUT == 1
    out_depth = depth;
    out_id = id;
#endif
#if GBUFFER_LAYOUT == 3
    float l = length(velocity);
    vec2 d = l > u_max_disp ? velocity * (u_max_disp / l) : velocity;
    out_hybrid_front = vec4(d, depth, float(id));    // ids are exact as floats below 2^24
#endif
}
