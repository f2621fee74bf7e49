#version 330 core
// The hybrid's inverse-motion composite (docs/algorithms.md 7.1): for u_samples times of
// the exposure (stratified, one jitter per pixel), what covers this pixel then, found by
// mapping the pixel back to the frame time along each candidate's own motion:
// - a rigid object (a mover, or every still object under the camera's own motion): the
//   pixel's ray at time t_k, in the object's own space (L_k = (V(t_k) M(t_k))^-1), must
//   meet the object's box; its point at a depth guess (where it enters the box, or the
//   pixel's own depth for its own object) is seen at the frame time at q = proj(V(t)
//   M(t) x); accepted when the G-buffer there holds that object with the point's depth
//   (within u_depth_tolerance) or a surface point that maps back within u_tolerance px,
//   the guess refined once from the depth read at q;
// - a skinned mover (no rigid map): the fixed point of q = p - u D(q) along its
//   displacement;
// - the pixel's own still surface under a still camera: there at every time.
// Of the surfaces that cover, the nearest wins; where none does, what the pixel's own
// mover hid: the revealed layer, else the pixel's own colour. The average over the
// samples is the pixel (linear light). Table and candidates: viewer/render/modes/hybrid/
// inverse.py.
#include "graph/noise.glsl"
#include "modes/hybrid/hybrid_layers.glsl"
#include "modes/hybrid/inverse_common.glsl"
uniform usampler2D u_candidates;
uniform int u_samples;
uniform bool u_camera_moves;
out vec4 out_color;

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    g_centre = vec2(x) + 0.5;
    g_ray = ray_at(g_centre);
    vec4 fx = texelFetch(u_front, x, 0);
    int own = int(fx.w + 0.5);
    int own_kind = kind_of(own);
    vec3 own_colour = front_colour(x);
    vec4 bx = texelFetch(u_back, x, 0);
    bool revealed = bx.w > 0.5;
    vec3 hidden = revealed ? back_colour(x) : own_colour;
    float hidden_depth = revealed ? bx.z : 3.0e38;
    uvec4 cand = texelFetch(u_candidates, x / FINE_TILE, 0);
    float j = ign(vec2(x), float(JITTER_STREAM));
    vec3 sum = vec3(0.0);
    for (int s = 0; s < u_samples; ++s) {
        float f = (float(s) + j) / float(u_samples);
        locate(f);
        float best = 3.0e38;
        vec3 colour = own_colour;
        float d;
        ivec2 at;
        bool found = false;
        if (own_kind == 0 && !u_camera_moves) {
            best = fx.z;
            found = true;
        } else if (own == 0) {
            found = sky(at);
            if (found) colour = front_colour(at);
        } else if (covers(own, own_kind, f, fx.z, d, at)) {
            best = d;
            colour = front_colour(at);
            found = true;
        }
        for (int i = 0; i < MAX_CANDIDATES; ++i) {
            int id = int(cand[i]);
            if (id == 0) break;
            if (id == own) continue;
            if (covers(id, kind_of(id), f, -1.0, d, at) && d < best) {
                best = d;
                colour = front_colour(at);
                found = true;
            }
        }
        if (own_kind != 0 && hidden_depth < best) colour = hidden;
        else if (!found) colour = hidden;
        sum += colour;
    }
    out_color = vec4(sum / float(u_samples), 1.0);
}
