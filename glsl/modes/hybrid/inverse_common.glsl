// Inverse motion (docs/algorithms.md 6.1), shared by the ray mask and the composite:
// which surface of an object covers this pixel at one of the table's times of the
// exposure, found in the G-buffer at the frame time along the object's own motion (the
// table and its layout: viewer/render/modes/hybrid/inverse.py). The includer declares
// u_front (the packed front layer: D, depth, id) and u_max_disp, and calls begin_pixel().
uniform sampler2D u_table;
uniform vec2 u_focal;
uniform vec2 u_viewport;
uniform float u_near;
uniform int u_parts;               // K: the table's times, the centres of K equal parts
uniform float u_tolerance;
uniform float u_depth_tolerance;

vec2 g_centre;
vec3 g_ray;                        // this pixel's view ray at its own time, z = -1

vec2 to_window(vec3 v) { return (u_focal * v.xy / -v.z * 0.5 + 0.5) * u_viewport; }
vec3 ray_at(vec2 window) { return vec3((window / u_viewport * 2.0 - 1.0) / u_focal, -1.0); }

void begin_pixel(ivec2 x) {
    g_centre = vec2(x) + 0.5;
    g_ray = ray_at(g_centre);
}

bool on_screen(vec2 q) {
    return all(greaterThanEqual(q, vec2(0.0))) && all(lessThan(q, u_viewport));
}

// Table access: texel `col` of time k, or of the object's own texels after the times'.
vec4 at_time(int id, int k, int col) {
    return texelFetch(u_table, ivec2(k * TABLE_COLS + col, id), 0);
}
vec4 own_texel(int id, int col) {
    return texelFetch(u_table, ivec2(u_parts * TABLE_COLS + col, id), 0);
}
int kind_of(int id) { return int(own_texel(id, AT_KIND).x + 0.5); }

// An affine map stored as its top three rows, applied to a point (w = 1) or a direction.
struct Affine { vec4 r0; vec4 r1; vec4 r2; };
Affine affine(int id, int k, int col) {
    return Affine(at_time(id, k, col), at_time(id, k, col + 1), at_time(id, k, col + 2));
}
vec3 apply(Affine m, vec4 p) { return vec3(dot(m.r0, p), dot(m.r1, p), dot(m.r2, p)); }

// Time index of stratum s of n at jitter j in [0, 1): the table time it falls in.
int part_of(int s, int n, float j) {
    return min(int((float(s) + j) * float(u_parts) / float(n)), u_parts - 1);
}

// Whether the object's screen box at time k holds this pixel.
bool in_box(int id, int k) {
    vec4 b = at_time(id, k, AT_BOX);
    return all(greaterThanEqual(g_centre, b.xy)) && all(lessThanEqual(g_centre, b.zw));
}

// Whether the G-buffer's object `seen` is object `id` (a still object: any still one).
bool same(int id, bool still, int seen) {
    return still ? kind_of(seen) == KIND_STILL : seen == id;
}

// A rigid object's surface on this pixel at time k: its view depth then and where the
// G-buffer holds it. The pixel's ray in the object's own space (L_k) must meet its box.
// Each start puts the ray's point at a depth d, maps it to the frame time (F_k) and reads
// the G-buffer there: accepted where that holds the object with the point's depth
// (within u_depth_tolerance) or a surface point that maps back (B_k) within u_tolerance
// px; else d is refined once from what was read. Starts: `guess` where given (the
// pixel's own depth for its own object), then where the ray enters the box and its
// middle (a round body's silhouette lies deep in its box).
bool rigid(int id, int kind, int k, float guess, out float depth, out ivec2 at) {
    bool still = kind == KIND_STILL;
    float t0 = u_near, t1 = 3.0e38;
    if (!still) {
        Affine l = affine(id, k, AT_L);
        vec3 o = vec3(l.r0.w, l.r1.w, l.r2.w);           // the eye, in local space
        vec3 r = apply(l, vec4(g_ray, 0.0));             // the ray's step per unit depth
        vec3 inv = 1.0 / r;                              // (IEEE: +-inf along an axis)
        vec3 a = (own_texel(id, AT_LO).xyz - o) * inv, b = (own_texel(id, AT_HI).xyz - o) * inv;
        vec3 near_t = min(a, b), far_t = max(a, b);
        t0 = max(t0, max(near_t.x, max(near_t.y, near_t.z)));
        t1 = min(far_t.x, min(far_t.y, far_t.z));
        if (!(t0 <= t1)) return false;
    }
    Affine f = affine(id, k, AT_F);
    Affine b = affine(id, k, AT_B);
    bool guessed = guess > 0.0 || still;
    int starts = still ? 1 : (guessed ? 3 : 2);
    float d = 0.0;
    for (int it = 0; it < 2 * starts; ++it) {
        if (it % 2 == 0) {
            int n = guessed ? it / 2 - 1 : it / 2;
            d = n < 0 ? clamp(guess, t0, t1) : mix(t0, t1, 0.5 * float(n));
        }
        // A miss goes on to the next start (`it |= 1`): a refinement from the same d
        // would miss the same way.
        vec3 y = apply(f, vec4(g_ray * d, 1.0));
        vec2 q = to_window(y);
        if (-y.z < u_near || !on_screen(q)) {
            it |= 1;
            continue;
        }
        ivec2 qi = ivec2(q);
        vec4 g = texelFetch(u_front, qi, 0);
        if (!same(id, still, int(g.w + 0.5))) {
            it |= 1;
            continue;
        }
        vec3 x = apply(b, vec4(ray_at(vec2(qi) + 0.5) * g.z, 1.0));
        if (-x.z < u_near) {
            it |= 1;
            continue;
        }
        vec2 back = to_window(x) - g_centre;
        if (abs(g.z + y.z) <= u_depth_tolerance * g.z
            || max(abs(back.x), abs(back.y)) <= u_tolerance) {
            depth = -x.z;
            at = qi;
            return true;
        }
        d = clamp(-x.z, t0, t1);
    }
    return false;
}

// A skinned object (no rigid map): the fixed point of q = p - u D(q) on its own
// displacement, u the time's offset from the frame time (a fraction of the exposure).
bool walked(int id, int k, out float depth, out ivec2 at) {
    float u = (float(k) + 0.5) / float(u_parts) - 0.5;
    vec2 p = g_centre;
    for (int it = 0; it < 3; ++it) {
        if (!on_screen(p)) return false;
        ivec2 qi = ivec2(floor(p));
        vec4 g = texelFetch(u_front, qi, 0);
        float l = length(g.xy);
        if (l > u_max_disp) g.xy *= u_max_disp / l;
        vec2 land = vec2(qi) + 0.5 + u * g.xy - g_centre;
        if (int(g.w + 0.5) == id && max(abs(land.x), abs(land.y)) <= u_tolerance) {
            depth = g.z;
            at = qi;
            return true;
        }
        p = g_centre - u * g.xy;
    }
    return false;
}

// Object `id` (of `kind`) on this pixel at time k, found at G-buffer pixel `at`, and its
// view depth then.
bool covers(int id, int kind, int k, float guess, out float depth, out ivec2 at) {
    if (kind == KIND_SKINNED) return walked(id, k, depth, at);
    return rigid(id, kind, k, guess, depth, at);
}

// The background under a camera's own motion at time k: the direction, at infinity.
bool sky(int k, out ivec2 at) {
    vec3 y = apply(affine(0, k, AT_F), vec4(g_ray, 0.0));
    if (-y.z <= 0.0) return false;
    vec2 q = to_window(y);
    if (!on_screen(q)) return false;
    ivec2 qi = ivec2(q);
    if (texelFetch(u_front, qi, 0).w > 0.5) return false;
    at = qi;
    return true;
}
