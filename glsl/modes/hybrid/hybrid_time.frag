#version 330 core
// The hybrid mode's time-sampled composite (docs/algorithms.md 4.3), the paper's "target pixel
// at the end of its sampling range" generalised to a centred exposure. For n stratified
// times u in the exposure (u in [-1/2, 1/2] of the shutter), find which surface lies on
// this pixel: on each layer, map the pixel back to the frame time along that layer's own
// motion (the fixed point of p = x - u D(p), started from a seed velocity and refined up
// to u_iterations times, keeping the pixel that lands closest); the surface found covers
// the pixel at time u if its own motion carries it within u_tolerance px of the pixel
// centre. Of the surfaces that cover,
// the nearest wins. Seeds: on the front layer the pixel's own displacement (its own
// object) and up to MAX_SEEDS distinct tile maxima of the 3x3 tiles around it, the
// neighbourhood's largest first (whatever may pass over it); on each back layer its
// displacement at the pixel (what the moving foreground uncovers). Where nothing
// covers (data missing: unmasked inner blur, off-screen), the closest miss stands in,
// preferring surfaces behind the pixel's own. The average over the times is the pixel.
// With a path (SEGMENTS > 1, glsl/passes/path.glsl) the front layer's motion at time u is its
// path's offset there, not u D.
#include "graph/noise.glsl"
#include "modes/hybrid/hybrid_layers.glsl"
#if SEGMENTS > 1
#define PATH_READ
#include "passes/path.glsl"
#endif
uniform sampler2D u_neighbormax;    // largest displacement over the 3x3 tiles
uniform sampler2D u_tilemax;        // largest displacement per tile
uniform sampler2D u_mask_tiles;     // ray_mask_tiles (hybrid/composite.py): y = 1 if a tile has rays
uniform int u_tile;
uniform int u_samples_min;
uniform int u_samples_max;
uniform float u_spacing;
uniform float u_jitter;
uniform float u_tolerance;
uniform int u_iterations;
out vec4 out_color;

ivec2 g_size;
vec2 g_centre;
float g_own_depth;

vec4 motion(int layer, ivec2 p) {
    if (layer == 0) return front_motion(p);
    return back_motion(p);
}

vec3 colour(int layer, ivec2 p) {
    if (layer == 0) return front_colour(p);
    return back_colour(p);
}

// Where the surface of `layer` at pixel q (motion m) lies at time u, from its frame-time
// position: u D, or on the front layer its path's offset.
vec2 offset_at(int layer, ivec2 q, vec4 m, float u) {
#if SEGMENTS > 1
    if (layer == 0) {
        vec2 o[PATH_POINTS];
        front_path_raw(q, o);
        clamp_path(o, u_max_disp);
        return path_at(o, u);
    }
#endif
    return u * m.xy;
}

// The frame-time pixel q of `layer` whose surface lies on this pixel at time u; returns
// how far (Chebyshev, px) its own motion carries it from the pixel centre. The walk keeps
// the pixel that lands closest; a pixel reached from off-screen counts as no data (1e30).
float walk(int layer, float u, vec2 seed, out ivec2 q, out vec4 m) {
    vec2 p = g_centre - u * seed;
    float best = 3.0e38;
    for (int it = 0; it <= u_iterations; ++it) {
        ivec2 raw = ivec2(floor(p));
        ivec2 qi = clamp(raw, ivec2(0), g_size - 1);
        vec4 mi = motion(layer, qi);
        vec2 off = offset_at(layer, qi, mi, u);
        vec2 land = vec2(qi) + 0.5 + off - g_centre;
        float r = raw == qi ? max(abs(land.x), abs(land.y)) : 1e30;
        if (r < best) { best = r; q = qi; m = mi; }
        p = g_centre - off;
        if (ivec2(floor(p)) == raw) break;     // a fixed point: the next steps repeat it
    }
    return best;
}

// Per time sample: the nearest covering surface, and the best stand-in if none covers.
float g_best_depth;
vec3 g_best;
bool g_covered;
float g_miss;
bool g_miss_behind;
vec3 g_stand_in;

void consider(int layer, float u, vec2 seed) {
    ivec2 q;
    vec4 m;
    float r = walk(layer, u, seed, q, m);
    if (r <= u_tolerance) {
        if (m.z < g_best_depth) {
            g_best_depth = m.z;
            g_best = colour(layer, q);
            g_covered = true;
        }
    } else if (!g_covered && r < 1e29) {
        bool behind = m.z > g_own_depth;
        if ((behind && !g_miss_behind) || (behind == g_miss_behind && r < g_miss)) {
            g_miss_behind = behind;
            g_miss = r;
            g_stand_in = colour(layer, q);
        }
    }
}

vec2 clamp_length(vec2 d) {
    float l = length(d);
    return l > u_max_disp ? d * (u_max_disp / l) : d;
}

// Seeds closer than this (px, per axis) lead the walk to the same surface: one is enough.
const float SEED_MERGE = 1.0;
vec2 g_seeds[MAX_SEEDS];
int g_num_seeds;

void add_seed(vec2 v, vec2 own) {
    if (g_num_seeds == MAX_SEEDS || length(v) <= 1.0) return;
    if (all(lessThan(abs(v - own), vec2(SEED_MERGE)))) return;
    for (int i = 0; i < g_num_seeds; ++i) {
        if (all(lessThan(abs(v - g_seeds[i]), vec2(SEED_MERGE)))) return;
    }
    g_seeds[g_num_seeds++] = v;
}

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    g_size = textureSize(u_front, 0);
    g_centre = vec2(x) + 0.5;
    vec3 own = front_colour(x);
    vec4 fx = front_motion(x);
    vec4 bx = back_motion(x);
    ivec2 tile = x / u_tile;
    vec2 vn = clamp_length(texelFetch(u_neighbormax, tile, 0).xy);
    float reach = max(length(vn), max(length(fx.xy), length(bx.xy)));
    // Nothing within reach moves half a pixel either way: the sharp pixel is the answer.
    if (reach <= 1.0) {
        out_color = vec4(own, 1.0);
        return;
    }
    g_own_depth = fx.z;
    // Where no ray was cast within reach, the back layer is the raster and its walk would
    // repeat the own one exactly: skip it.
    bool back_walk = bx.w > 0.5;
    g_num_seeds = 0;
    add_seed(vn, fx.xy);
    ivec2 tiles = textureSize(u_tilemax, 0);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 t = tile + ivec2(dx, dy);
            if (all(greaterThanEqual(t, ivec2(0))) && all(lessThan(t, tiles))) {
                add_seed(clamp_length(texelFetch(u_tilemax, t, 0).xy), fx.xy);
                back_walk = back_walk || texelFetch(u_mask_tiles, t, 0).y > 0.0;
            }
        }
    }
    int n = clamp(int(ceil(reach / u_spacing)), u_samples_min, u_samples_max);
    float j = mix(0.5, hash01(x, JITTER_STREAM), u_jitter);
    vec3 sum = vec3(0.0);
    for (int k = 0; k < n; ++k) {
        float u = (float(k) + j) / float(n) - 0.5;
        g_best_depth = 3.0e38;
        g_covered = false;
        g_miss = 3.0e38;
        g_miss_behind = false;
        g_stand_in = own;
        consider(0, u, fx.xy);
        for (int i = 0; i < g_num_seeds; ++i) consider(0, u, g_seeds[i]);
        if (back_walk) consider(1, u, bx.xy);
        sum += g_covered ? g_best : g_stand_in;
    }
    out_color = vec4(sum / float(n), 1.0);
}
