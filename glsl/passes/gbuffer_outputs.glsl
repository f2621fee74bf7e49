// G-buffer render targets. GBUFFER_LAYOUT picks which are written: one of the codes
// GBUFFER_LAYOUT_<NAME> of viewer/render/passes/gbuffer.py's LAYOUTS (injected). FULL = all,
// VISIBILITY = colour, depth and id (reference sub-frames that record visibility), COLOR =
// colour only (plain reference sub-frames), HYBRID = the hybrid mode's: colour, normal and
// the packed front layer (D, depth, id) that every hybrid pass reads, one fetch for all
// three (every target written costs per fragment on llvmpipe: docs/architecture.md);
// FRONT = colour and the packed front layer (the hybrid mode's without the poster's edge
// test, which alone reads the normal target; and the static objects' layer that the
// hybrid reveal copies where a ray's first hit is static: viewer/render/modes/hybrid/reveal.py);
// MOTION = colour, depth and displacement (the post-process filters').
#define GBUFFER_FULL (GBUFFER_LAYOUT == GBUFFER_LAYOUT_FULL)
#define GBUFFER_HYBRID (GBUFFER_LAYOUT == GBUFFER_LAYOUT_HYBRID)
#define GBUFFER_FRONT (GBUFFER_LAYOUT == GBUFFER_LAYOUT_FRONT)
#define GBUFFER_PACKED (GBUFFER_HYBRID || GBUFFER_FRONT)
// GBUFFER_MOTION: D is written.
#define GBUFFER_MOTION (GBUFFER_FULL || GBUFFER_PACKED || GBUFFER_LAYOUT == GBUFFER_LAYOUT_MOTION)
layout(location = 0) out vec4 out_color;         // linear, unclamped
#if GBUFFER_FULL
layout(location = 1) out float out_depth;        // linear view depth
layout(location = 2) out vec4 out_normal;        // world normal, facing the camera
layout(location = 3) out uint out_id;            // object id (0 = background)
layout(location = 4) out vec2 out_velocity;      // pixels over the exposure, GL axes
#elif GBUFFER_LAYOUT == GBUFFER_LAYOUT_VISIBILITY
layout(location = 1) out float out_depth;
layout(location = 2) out uint out_id;
#elif GBUFFER_LAYOUT == GBUFFER_LAYOUT_HYBRID
layout(location = 1) out vec4 out_normal;
// (D.xy, depth, id): glsl/modes/hybrid/hybrid_layers.glsl's front layer (D not clamped: its readers
// clamp it to the blur limit where they need to).
layout(location = 2) out vec4 out_hybrid_front;
#elif GBUFFER_LAYOUT == GBUFFER_LAYOUT_FRONT
layout(location = 1) out vec4 out_hybrid_front;
#elif GBUFFER_LAYOUT == GBUFFER_LAYOUT_MOTION
layout(location = 1) out float out_depth;
layout(location = 2) out vec2 out_velocity;
#endif
// The path targets (glsl/passes/path.glsl), after the layout's own: at PATH_LOCATION(1).
#if SEGMENTS > 1
layout(location = PATH_LOCATION) out vec4 out_path0;
#if SEGMENTS == 4
layout(location = PATH_LOCATION1) out vec4 out_path1;
#endif
#endif
// The static objects' kept raster (viewer/render/passes/static_raster.py) also writes each
// pixel's static draw rank (1 + its place in the draw order, 0 = background), last.
#ifdef RANK_LOCATION
layout(location = RANK_LOCATION) out uint out_rank;
#endif

void write_gbuffer(vec3 color, float depth, vec3 normal, uint id, vec2 velocity) {
    out_color = vec4(color, 1.0);
#if GBUFFER_FULL
    out_depth = depth;
    out_normal = vec4(normal, 0.0);
    out_id = id;
    out_velocity = velocity;
#elif GBUFFER_LAYOUT == GBUFFER_LAYOUT_VISIBILITY
    out_depth = depth;
    out_id = id;
#elif GBUFFER_LAYOUT == GBUFFER_LAYOUT_HYBRID
    // w: log view depth (half float: steps of ~0.1%), what the ray mask's edge test reads
    // per neighbour: one fetch of this target, no log there (glsl/modes/hybrid/raymask_displacement.frag).
    out_normal = vec4(normal, log(max(depth, 1e-6)));
    out_hybrid_front = vec4(velocity, depth, float(id));   // ids are exact as floats below 2^24
#elif GBUFFER_LAYOUT == GBUFFER_LAYOUT_FRONT
    out_hybrid_front = vec4(velocity, depth, float(id));
#elif GBUFFER_LAYOUT == GBUFFER_LAYOUT_MOTION
    out_depth = depth;
    out_velocity = velocity;
#endif
}
