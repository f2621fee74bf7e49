#version 330 core
// Ray mask, step 3: the range check. A moving pixel samples along its displacement, both
// ways, one pixel per step; if a sample is an edge pixel of its own object within reach
// (half the larger of the pixel's displacement and that edge's relative displacement, in
// whole steps), the pixel is masked. Survivors of the displacement test are masked too. The output is
// the pixel's object id where masked (0 elsewhere): one read gives mask and own ids.
// A coarse look along the search at the 16-px tiles with an edge nearby (edge_ids.frag)
// skips it where it would find nothing, and bounds it by the largest reach of the edges
// it passes: the result is the same, the cost far lower where everything moves (camera
// motion) but few edges survive.
#include "modes/hybrid/raymask_common.glsl"
uniform usampler2D u_displacement_mask;
uniform sampler2D u_edge_probe;   // raymask_displacement.frag: (half |relative D|, id) at edges
uniform sampler2D u_front;        // the G-buffer's hybrid_front: (D, depth, id)
uniform usampler2D u_edge_near;   // .x bit (id mod 32): an edge of that object in this
                                  // FINE tile or one next to it; .y the bits of the
                                  // largest reach of an edge there (edge_ids.frag)
uniform usampler2D u_edge_reach;  // .x: the same bits over every tile a probe can reach
uniform float u_min_speed;
uniform float u_relative_reach;   // search length, in half displacements
uniform float u_max_reach;        // the blur limit k, px per side
// FINE (a define, not a uniform: llvmpipe divides by a uniform lane by lane): the tile
// size of u_edge_near and u_edge_reach.
out uint out_mask;

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_front, 0);
    vec4 f = texelFetch(u_front, x, 0);
    uint own = uint(f.w);
    vec2 d = f.xy;
    out_mask = 0u;
    if (own == 0u || length(d) < u_min_speed) return;
    if (texelFetch(u_displacement_mask, x, 0).x != 0u) { out_mask = own; return; }
#if REACH_TEST
    // No edge of the own object anywhere in reach: no search (one read, not the look).
    if ((texelFetch(u_edge_reach, x / FINE, 0).x & (1u << (own % 32u))) == 0u) return;
#endif
    float half_len = 0.5 * length(d);
    vec2 dir = d / length(d);
    float full = min(u_max_reach, u_relative_reach * half_len);
    // Coarse look first: points every 2 FINE px along the search. A probe lies within
    // FINE px of one, per axis too, and so within FINE px after flooring and clamping, so
    // its tile is within a tile of that point's: where no point's tile has an edge of the
    // own object next to it, no probe sees one; and an edge a probe accepts has a reach no
    // larger than the largest those points see.
    uint own_bit = 1u << (own % 32u);
    bool any_edge = false;
    float reach_seen = 0.0;
    const int spacing = 2 * FINE;
    int m_max = (int(ceil(full)) + spacing - 1) / spacing;
    for (int m = -m_max; m <= m_max; ++m) {
        uvec2 t = texelFetch(u_edge_near, probe(x, float(spacing * m) * dir, size) / FINE, 0).xy;
        bool own_edge = (t.x & own_bit) != 0u;
        any_edge = any_edge || own_edge;
        reach_seen = max(reach_seen, own_edge ? uintBitsToFloat(t.y) : 0.0);
    }
    if (!any_edge) return;
    int steps = int(ceil(min(full, max(half_len, reach_seen))));
    float own_f = float(own);
    for (int i = 0; i <= steps; ++i) {
        for (int s = -1; s <= 1; s += 2) {
            vec2 e = texelFetch(u_edge_probe, probe(x, float(s * i) * dir, size), 0).xy;
            if (e.y == own_f && float(i) <= min(max(half_len, e.x), u_max_reach)) {
                out_mask = own;
                return;
            }
        }
    }
}
