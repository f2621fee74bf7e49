#version 330 core
// The hybrid's inverse-motion composite (docs/algorithms.md 6.1): for u_samples times of
// the exposure (stratified over the table's K times, one interleaved-gradient jitter per
// pixel), what covers this pixel then, found by mapping the pixel back to the frame time
// along each candidate's own motion:
// - a rigid object (a mover, or every still object under the camera's own motion): the
//   pixel's ray at time t_k, in the object's own space (L_k = (V(t_k) M(t_k))^-1), must
//   meet the object's box (and the pixel lie in its screen box then); its point at a depth
//   guess (where it enters the box, or the
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
uniform sampler2D u_neighbormax;    // the largest displacement over the 3x3 tiles around
uniform int u_tile;
uniform int u_samples;
uniform float u_spacing;
uniform bool u_camera_moves;
out vec4 out_color;

// What the pixel's own mover hid, at time k: the revealed layer's surface. It is still
// (a mover behind a mover is its own candidate); under the camera's own motion it moves
// with the camera: mapped by the still map to q, read from the revealed layer there, or
// from the raster where q shows a still surface at the frame time.
vec3 behind(vec4 bx, int k, vec3 fallback) {
    if (!u_camera_moves) return fallback;
    vec3 y = apply(affine(0, k, AT_F), vec4(g_ray * bx.z, 1.0));
    if (-y.z < u_near) return fallback;
    vec2 q = to_window(y);
    if (!on_screen(q)) return fallback;
    ivec2 qi = ivec2(q);
    vec4 b = texelFetch(u_back, qi, 0);
    if (b.w > 0.5) return texelFetch(u_back_color, qi, 0).rgb;
    vec4 f = texelFetch(u_front, qi, 0);
    return kind_of(int(f.w + 0.5)) == KIND_STILL ? front_colour(qi) : fallback;
}

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    begin_pixel(x);
    vec4 fx = texelFetch(u_front, x, 0);
    vec3 own_colour = front_colour(x);
    int own = int(fx.w + 0.5);
    int own_kind = kind_of(own);
    // The pixel's own surface is there at every time where neither it nor the camera
    // moves; the sky under a moving camera is looked up by direction.
    bool own_stays = own_kind == KIND_STILL && !u_camera_moves;
    vec4 bx = texelFetch(u_back, x, 0);
    bool revealed = bx.w > 0.5;
    vec3 hidden = revealed ? back_colour(x) : own_colour;
    float hidden_depth = revealed ? bx.z : 3.0e38;
    // The tile's other candidates whose screen box over the exposure holds the pixel,
    // with their kinds.
    uvec4 listed = texelFetch(u_candidates, x / FINE_TILE, 0);
    ivec4 ids = ivec4(0), kinds = ivec4(0);
    int n = 0;
    for (int i = 0; i < MAX_CANDIDATES; ++i) {
        int id = int(listed[i]);
        vec4 reach = own_texel(id, AT_REACH);
        if (id != 0 && id != own && all(greaterThanEqual(g_centre, reach.xy))
            && all(lessThanEqual(g_centre, reach.zw))) {
            ids[n] = id;
            kinds[n] = kind_of(id);
            ++n;
        }
    }
    // Samples by how far anything near moves: one per u_spacing px, at most u_samples.
    float reach = max(length(fx.xy), length(texelFetch(u_neighbormax, x / u_tile, 0).xy));
    int samples = clamp(int(ceil(reach / u_spacing)), 1, u_samples);
    float j = ign(vec2(x), float(JITTER_STREAM));
    vec3 sum = vec3(0.0);
    for (int s = 0; s < samples; ++s) {
        int k = part_of(s, samples, j);
        float best = 3.0e38;
        vec3 colour = own_colour;
        float d;
        ivec2 at;
        bool found = own_stays;
        if (own_stays) {
            best = fx.z;
        } else if (own == 0) {
            found = sky(k, at);
            if (found) colour = front_colour(at);
        } else if (covers(own, own_kind, k, fx.z, d, at)) {
            best = d;
            colour = front_colour(at);
            found = true;
        }
        for (int i = 0; i < n; ++i) {
            if (in_box(ids[i], k) && covers(ids[i], kinds[i], k, -1.0, d, at) && d < best) {
                best = d;
                colour = front_colour(at);
                found = true;
            }
        }
        if ((own_kind != KIND_STILL && hidden_depth < best) || !found)
            colour = revealed ? behind(bx, k, hidden) : hidden;
        sum += colour;
    }
    out_color = vec4(sum / float(samples), 1.0);
}
