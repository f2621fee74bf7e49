// Inverse motion (docs/algorithms.md 7.1), shared by the ray mask and the composite:
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

vec2 to_window(vec4 v) { return (u_focal * v.xy / -v.z * 0.5 + 0.5) * u_viewport; }
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
mat4 time_mat(int id, int k, int col) {
    return mat4(at_time(id, k, col), at_time(id, k, col + 1), at_time(id, k, col + 2),
                at_time(id, k, col + 3));
}
mat4 own_mat(int id, int col) {
    return mat4(own_texel(id, col), own_texel(id, col + 1), own_texel(id, col + 2),
                own_texel(id, col + 3));
}
int kind_of(int id) { return int(own_texel(id, 10).x + 0.5); }

// Time index of stratum s of n at jitter j in [0, 1): the table time it falls in.
int part_of(int s, int n, float j) {
    return min(int((float(s) + j) * float(u_parts) / float(n)), u_parts - 1);
}

// Whether the object's screen box at time k holds this pixel.
bool in_box(int id, int k) {
    vec4 b = at_time(id, k, 8);
    return all(greaterThanEqual(g_centre, b.xy)) && all(lessThanEqual(g_centre, b.zw));
}

// What the per-pixel search needs of one candidate, read once a pixel.
struct Candidate {
    int id;
    int kind;
    mat4 now;          // local -> view at the frame time: V(t) M(t)
    mat4 now_inv;
    vec3 lo;
    vec3 hi;
};

Candidate candidate(int id) {
    Candidate c;
    c.id = id;
    c.kind = kind_of(id);
    c.now = own_mat(id, 0);
    c.now_inv = own_mat(id, 4);
    c.lo = own_texel(id, 8).xyz;
    c.hi = own_texel(id, 9).xyz;
    return c;
}

// Whether the G-buffer's object `seen` is candidate c (a still object: any still one).
bool same(Candidate c, int seen) {
    return c.kind == 0 ? kind_of(seen) == 0 : seen == c.id;
}

// One start of rigid()'s search: the ray's point at depth d (o + r d, local space) seen
// at the frame time at q; accepted where the G-buffer there holds the object with that
// point's depth (within u_depth_tolerance) or a surface point that maps back within
// u_tolerance px; else the depth refined from what was read, and tried once more.
bool search(Candidate c, mat4 li, vec3 o, vec3 r, float d, float t0, float t1,
            out float depth, out ivec2 at) {
    for (int it = 0; it < 2; ++it) {
        vec4 y = c.now * vec4(o + r * d, 1.0);
        if (-y.z < u_near) return false;
        vec2 q = to_window(y);
        if (!on_screen(q)) return false;
        ivec2 qi = ivec2(q);
        vec4 f = texelFetch(u_front, qi, 0);
        if (!same(c, int(f.w + 0.5))) return false;
        vec4 x = li * (c.now_inv * vec4(ray_at(vec2(qi) + 0.5) * f.z, 1.0));
        if (-x.z < u_near) return false;
        vec2 back = to_window(x) - g_centre;
        if (abs(f.z + y.z) <= u_depth_tolerance * f.z
            || max(abs(back.x), abs(back.y)) <= u_tolerance) {
            depth = -x.z;
            at = qi;
            return true;
        }
        d = clamp(-x.z, t0, t1);
    }
    return false;
}

// A rigid candidate's surface on this pixel at time k: its view depth then and where the
// G-buffer holds it. The pixel's ray in the object's own space (L_k) must meet its box;
// the search starts at `guess` (the pixel's own depth for its own object), then where
// the ray enters the box, its middle and where it leaves (a round body's silhouette lies
// deep in its box).
bool rigid(Candidate c, int k, float guess, out float depth, out ivec2 at) {
    mat4 l = time_mat(c.id, k, 0);
    vec3 o = l[3].xyz;                                   // the eye, in local space
    vec3 r = (l * vec4(g_ray, 0.0)).xyz;                 // the ray's step per unit depth
    float t0 = u_near, t1 = 3.0e38;
    bool still = c.kind == 0;
    if (!still) {
        vec3 inv = 1.0 / r;                              // (IEEE: +-inf along an axis)
        vec3 a = (c.lo - o) * inv, b = (c.hi - o) * inv;
        vec3 near_t = min(a, b), far_t = max(a, b);
        t0 = max(t0, max(near_t.x, max(near_t.y, near_t.z)));
        t1 = min(far_t.x, min(far_t.y, far_t.z));
        if (!(t0 <= t1)) return false;
    }
    mat4 li = time_mat(c.id, k, 4);                      // local -> view at t_k
    if ((guess > 0.0 || still)
        && search(c, li, o, r, clamp(guess, t0, t1), t0, t1, depth, at))
        return true;
    if (still) return false;
    for (int n = 0; n < 3; ++n) {
        if (search(c, li, o, r, mix(t0, t1, 0.5 * float(n)), t0, t1, depth, at)) return true;
    }
    return false;
}

// A skinned candidate (no rigid map): the fixed point of q = p - u D(q) on its own
// displacement, u the time's offset from the frame time (a fraction of the exposure).
bool walked(Candidate c, float u, out float depth, out ivec2 at) {
    vec2 p = g_centre;
    for (int it = 0; it < 3; ++it) {
        if (!on_screen(p)) return false;
        ivec2 qi = ivec2(floor(p));
        vec4 f = texelFetch(u_front, qi, 0);
        float l = length(f.xy);
        if (l > u_max_disp) f.xy *= u_max_disp / l;
        vec2 land = vec2(qi) + 0.5 + u * f.xy - g_centre;
        if (int(f.w + 0.5) == c.id && max(abs(land.x), abs(land.y)) <= u_tolerance) {
            depth = f.z;
            at = qi;
            return true;
        }
        p = g_centre - u * f.xy;
    }
    return false;
}

// Candidate c's surface on this pixel at time k, found at G-buffer pixel `at`, and its
// view depth then.
bool covers(Candidate c, int k, float guess, out float depth, out ivec2 at) {
    if (c.kind == 2) return walked(c, (float(k) + 0.5) / float(u_parts) - 0.5, depth, at);
    return rigid(c, k, guess, depth, at);
}

// The background under a camera's own motion at time k: the direction, at infinity.
bool sky(int k, out ivec2 at) {
    vec4 y = own_mat(0, 0) * (time_mat(0, k, 0) * vec4(g_ray, 0.0));
    if (-y.z <= 0.0) return false;
    vec2 q = to_window(y);
    if (!on_screen(q)) return false;
    ivec2 qi = ivec2(q);
    if (texelFetch(u_front, qi, 0).w > 0.5) return false;
    at = qi;
    return true;
}
