#version 330 core
// Ray mask, step 1: the displacement test (docs/algorithms.md 4.1-4.2), for a centred exposure.
// A moving pixel X of object I with displacement D is uncovered at shutter open if the
// point at X + D/2 lies off I, and at shutter close if X - D/2 does; it is kept when that
// probe sees a different object farther than X (by a relative threshold). Both ways.
// Where the camera moves the background moves too, and what X's background blur needs
// lies within half the RELATIVE displacement D - D_bg of the silhouette: the first probe
// that sees the background gives D_bg, and X +- (D - D_bg)/2 is tested as well.
// Outputs: the test's result and the relative displacement (D where no background was seen).
// STEP 3 (the default mask) keeps only the relative test's survivors: the surface hidden
// behind X at the frame time shows at some time of the exposure iff X +- (D - D_bg)/2
// leaves X's object, whatever D alone does (the same test where the background is
// still); where D and D_bg are alike (a camera pan's parallax) the band is far
// narrower. The background seen at X while X's object is away, at X - u D_bg, is then
// either visible at the frame time (the raster has it) or hidden and itself masked.
//
// Ray mask, step 2, in the same pass (it needs nothing but this pixel's step 1): the edge
// test. Survivors of the displacement test are kept where a Sobel kernel on log depth or
// on the world normal exceeds its threshold: the moving silhouettes (and creases next to
// them). Both come from the G-buffer's normal target, (normal, log depth) at half
// precision (glsl/passes/gbuffer_outputs.glsl): one fetch per neighbour. The kernel is divided by 4, so a one-pixel step of size s reads as s.
// Outputs: the edge flag, and for the range check's inner loop (one fetch per probe)
// (half the relative displacement, the object id) at an edge pixel, (0, 0) elsewhere (id
// 0 is the sky, never a searching pixel's own).
//
// With a path (SEGMENTS > 1, glsl/passes/path.glsl) the probes follow it: X's surface lies at
// X + o_k at the path's time t_k, so X then shows what lies at X - o_k now; each of the
// path's points is probed (a reversal's far point too, where the chord is short), the
// relative ones at X - (o_k - o_bg,k), and the speed test reads the path's extent.
//
// With INVERSE_CHECKS (the hybrid following curves, on the tiles they reach) a moving
// pixel is also kept where its own mover leaves it at one of that many evenly spaced
// times (glsl/modes/hybrid/inverse_common.glsl): a reversal or an arc the chord misses.
//
// STEP 0 runs both steps in one pass. Where the camera moves, most moving tiles hold no
// survivor of step 1 and llvmpipe would pay the Sobel kernel in every 8-pixel group
// holding one: STEP 1 then runs the displacement test alone, and STEP 2 the edge test on
// the tiles that hold a survivor (viewer/render/modes/hybrid/mask.py). STEP 3 is the mask without
// the range check (hybrid.range_check off): the displacement test alone, its survivors
// written straight into the ray mask as their object ids.
#include "modes/hybrid/raymask_common.glsl"
#define DISPLACEMENT_TEST (STEP != 2)
#define EDGE_TEST (STEP == 0 || STEP == 2)
uniform sampler2D u_front;          // the G-buffer's hybrid_front: (D, depth, id)
#if DISPLACEMENT_TEST
uniform float u_min_speed;          // px over the exposure
uniform float u_depth_threshold;    // relative
#if STEP == 3
layout(location = 0) out uint out_ray_mask;
uint out_mask;                      // (the test's results, not targets here)
vec2 out_relative;
#else
layout(location = 0) out uint out_mask;
layout(location = 1) out vec2 out_relative;
#endif
#endif
#if EDGE_TEST
uniform sampler2D u_normal;         // the G-buffer's (normal, log depth)
uniform float u_edge_depth;
uniform float u_edge_normal;
#if STEP == 0
layout(location = 2) out uint out_edge;
layout(location = 3) out vec2 out_probe;
#else
layout(location = 0) out uint out_edge;
layout(location = 1) out vec2 out_probe;
#endif
#endif
#if SEGMENTS > 1 && DISPLACEMENT_TEST
#define PATH_READ
#include "passes/path.glsl"
#endif
#if STEP == 2
uniform usampler2D u_displacement_mask;
uniform sampler2D u_relative;
#endif

#if DISPLACEMENT_TEST
float own_id;
float own_depth;

// Does the pixel at x + offset show another object farther than x? Its velocity in v.
bool uncovers(ivec2 x, vec2 offset, ivec2 size, out vec2 v) {
    vec4 f = texelFetch(u_front, probe(x, offset, size), 0);
    v = f.xy;
    return f.w != own_id && f.z > own_depth * (1.0 + u_depth_threshold);
}

// Step 1 at x: out_mask and out_relative.
#if SEGMENTS > 1
void displacement_test(ivec2 x, ivec2 size) {
    vec4 f = texelFetch(u_front, x, 0);
    own_id = f.w;
    own_depth = f.z;
    out_mask = 0u;
    out_relative = f.xy;
    vec2 o[PATH_POINTS];
    front_path_raw(x, o);
    if (own_id == 0.0 || path_extent(o) < u_min_speed) return;
    vec2 vb;
    bool found = false;
    ivec2 at = x;
    for (int k = 0; k < PATH_POINTS; ++k) {
        if (k == SEGMENTS / 2) continue;            // the frame time: X itself
        if (uncovers(x, -o[k], size, vb)) {
#if STEP != 3
            out_mask = 1u;
#endif
            if (!found) { at = probe(x, -o[k], size); found = true; }
        }
    }
    if (found) {
        vec2 b[PATH_POINTS];
        front_path_raw(at, b);
        out_relative = (o[SEGMENTS] - o[0]) - (b[SEGMENTS] - b[0]);
        for (int k = 0; k < PATH_POINTS; ++k) {
            if (k != SEGMENTS / 2 && uncovers(x, b[k] - o[k], size, vb)) out_mask = 1u;
        }
    }
}
#else
void displacement_test(ivec2 x, ivec2 size) {
    vec4 f = texelFetch(u_front, x, 0);
    vec2 d = f.xy;
    own_id = f.w;
    own_depth = f.z;
    out_mask = 0u;
    out_relative = d;
    if (own_id == 0.0 || length(d) < u_min_speed) return;   // the sky hides nothing
    vec2 vb;
    bool found = false;
    for (int s = -1; s <= 1; s += 2) {
        if (uncovers(x, 0.5 * float(s) * d, size, vb)) {
#if STEP != 3
            out_mask = 1u;                  // (the poster's test: X's object leaves X)
#endif
            if (!found) { out_relative = d - vb; found = true; }
        }
    }
    if (found) {
        for (int s = -1; s <= 1; s += 2) {
            if (uncovers(x, 0.5 * float(s) * out_relative, size, vb)) out_mask = 1u;
        }
    }
}
#endif
#endif

#if EDGE_TEST
// Step 2 at x: is it on a depth or normal edge?
bool on_edge(ivec2 x, ivec2 size) {
    vec2 gz = vec2(0.0);
    vec3 gnx = vec3(0.0), gny = vec3(0.0);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            if (dx == 0 && dy == 0) continue;
            ivec2 p = clamp(x + ivec2(dx, dy), ivec2(0), size - 1);
            // Sobel weights: 2 on the axis, 1 on the diagonals; sign by side.
            vec2 w = vec2(float(dx) * (dy == 0 ? 2.0 : 1.0), float(dy) * (dx == 0 ? 2.0 : 1.0));
            vec4 n = texelFetch(u_normal, p, 0);       // (world normal, log depth)
            gz += w * n.w;
            gnx += w.x * n.xyz;
            gny += w.y * n.xyz;
        }
    }
    float g_depth = 0.25 * length(gz);
    float g_normal = 0.25 * sqrt(dot(gnx, gnx) + dot(gny, gny));
    return g_depth > u_edge_depth || g_normal > u_edge_normal;
}
#endif

#ifdef INVERSE_CHECKS
uniform float u_max_disp;
#include "modes/hybrid/inverse_common.glsl"

// Whether the pixel's own mover covers it at every checked time.
bool stays(ivec2 x) {
    begin_pixel(x);
    int id = int(own_id + 0.5);
    int kind = kind_of(id);
    if (kind == KIND_STILL) return true;
    float d;
    ivec2 at;
    for (int i = 0; i < INVERSE_CHECKS; ++i) {
        if (!covers(id, kind, part_of(i, INVERSE_CHECKS, 0.5), own_depth, d, at)) return false;
    }
    return true;
}
#endif

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_front, 0);
#if DISPLACEMENT_TEST
    displacement_test(x, size);
#endif
#if STEP == 3
#ifdef INVERSE_CHECKS
    if (out_mask == 0u && own_id != 0.0 && !stays(x)) out_mask = 1u;
#endif
    out_ray_mask = out_mask != 0u ? uint(own_id) : 0u;
#endif
#if STEP == 0
    bool survivor = out_mask != 0u;
    vec2 relative = out_relative;
    float id = own_id;
#elif STEP == 2
    bool survivor = texelFetch(u_displacement_mask, x, 0).x != 0u;
    vec2 relative = texelFetch(u_relative, x, 0).xy;
    float id = texelFetch(u_front, x, 0).w;
#endif
#if EDGE_TEST
    out_edge = 0u;
    out_probe = vec2(0.0);
    if (survivor && on_edge(x, size)) {
        out_edge = 1u;
        out_probe = vec2(0.5 * length(relative), id);
    }
#endif
}
