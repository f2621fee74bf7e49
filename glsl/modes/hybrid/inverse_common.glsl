// Inverse motion (docs/algorithms.md 7.1), shared by the ray mask and the composite:
// which surface of an object covers this pixel at a time of the exposure, found in the
// G-buffer at the frame time along the object's own motion (the table and its layout:
// viewer/render/modes/hybrid/inverse.py). The includer declares u_front (the packed
// front layer: D, depth, id) and u_max_disp, and sets g_centre and g_ray per pixel.
uniform sampler2D u_table;
uniform vec2 u_focal;
uniform vec2 u_viewport;
uniform float u_near;
uniform int u_intervals;
uniform float u_tolerance;
uniform float u_depth_tolerance;

vec2 g_centre;

vec3 g_ray;                  // this pixel's view ray at its own time, z = -1

vec2 to_window(vec4 v) { return (u_focal * v.xy / -v.z * 0.5 + 0.5) * u_viewport; }
vec3 ray_at(vec2 window) { return vec3((window / u_viewport * 2.0 - 1.0) / u_focal, -1.0); }

// Per-object texels after the K + 1 times' (inverse.py: V(t) M(t), its inverse, lo, hi,
// kind).
int tail(int col) { return (u_intervals + 1) * TABLE_COLS + col; }
int kind_of(int id) { return int(texelFetch(u_table, ivec2(tail(10), id), 0).x + 0.5); }
mat4 fixed_mat(int id, int col) {
    return mat4(texelFetch(u_table, ivec2(tail(col), id), 0),
                texelFetch(u_table, ivec2(tail(col + 1), id), 0),
                texelFetch(u_table, ivec2(tail(col + 2), id), 0),
                texelFetch(u_table, ivec2(tail(col + 3), id), 0));
}

// The two table times around exposure fraction f, blended.
int g_k;
float g_w;
void locate(float f) {
    float x = f * float(u_intervals);
    g_k = min(int(x), u_intervals - 1);
    g_w = x - float(g_k);
}
vec4 entry(int id, int col) {
    vec4 a = texelFetch(u_table, ivec2(g_k * TABLE_COLS + col, id), 0);
    vec4 b = texelFetch(u_table, ivec2((g_k + 1) * TABLE_COLS + col, id), 0);
    return mix(a, b, g_w);
}
mat4 table_mat(int id, int col) {
    return mat4(entry(id, col), entry(id, col + 1), entry(id, col + 2), entry(id, col + 3));
}

bool on_screen(vec2 q) {
    return all(greaterThanEqual(q, vec2(0.0))) && all(lessThan(q, u_viewport));
}

// Whether the G-buffer's object `seen` is candidate `id` (a still object: any still one).
bool same(int id, int seen, bool still) {
    return still ? kind_of(seen) == 0 : seen == id;
}

// One start of rigid()'s search: the ray's point at depth d mapped to the frame time,
// the G-buffer read there, accepted when it holds the object with that point's depth
// (within u_depth_tolerance) or a surface point that maps back within u_tolerance px;
// else the depth refined from what was read, and tried once more.
bool search(int id, bool still, vec3 o, vec3 r, float d, float t0, float t1, mat4 now,
            mat4 now_inv, mat4 li, out float depth, out ivec2 at) {
    for (int it = 0; it < 2; ++it) {
        vec4 y = now * vec4(o + r * d, 1.0);
        if (-y.z < u_near) return false;
        vec2 q = to_window(y);
        if (!on_screen(q)) return false;
        ivec2 qi = ivec2(q);
        vec4 f = texelFetch(u_front, qi, 0);
        if (!same(id, int(f.w + 0.5), still)) return false;
        vec4 x = li * (now_inv * vec4(ray_at(vec2(qi) + 0.5) * f.z, 1.0));
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

// A rigid candidate's surface on this pixel at the time located: its view depth then and
// where the G-buffer holds it. The pixel's ray in the object's own space (L_k) must meet
// its box; the search starts at `guess` (the pixel's own depth for its own object), then
// where the ray enters the box, its middle and where it leaves (a round body's
// silhouette lies deep in its box).
bool rigid(int id, bool still, float guess, out float depth, out ivec2 at) {
    mat4 l = table_mat(id, 0);
    vec3 o = l[3].xyz;                                   // the eye, in local space
    vec3 r = (l * vec4(g_ray, 0.0)).xyz;                 // the ray's step per unit depth
    float t0 = u_near, t1 = 3.0e38;
    if (!still) {
        vec3 lo = texelFetch(u_table, ivec2(tail(8), id), 0).xyz;
        vec3 hi = texelFetch(u_table, ivec2(tail(9), id), 0).xyz;
        vec3 inv = 1.0 / r;                              // (IEEE: +-inf along an axis)
        vec3 a = (lo - o) * inv, b = (hi - o) * inv;
        vec3 near_t = min(a, b), far_t = max(a, b);
        t0 = max(t0, max(near_t.x, max(near_t.y, near_t.z)));
        t1 = min(far_t.x, min(far_t.y, far_t.z));
        if (!(t0 <= t1)) return false;
    }
    mat4 now = fixed_mat(id, 0);                         // local -> view at t
    mat4 now_inv = fixed_mat(id, 4);
    mat4 li = table_mat(id, 4);                          // local -> view at t_k
    if ((guess > 0.0 || still)
        && search(id, still, o, r, clamp(guess, t0, t1), t0, t1, now, now_inv, li, depth, at))
        return true;
    if (still) return false;
    for (int k = 0; k < 3; ++k) {
        float d = mix(t0, t1, 0.5 * float(k));
        if (search(id, still, o, r, d, t0, t1, now, now_inv, li, depth, at)) return true;
    }
    return false;
}

// The background under a camera's own motion: the direction, at infinity.
bool sky(out ivec2 at) {
    vec4 y = fixed_mat(0, 0) * (table_mat(0, 0) * vec4(g_ray, 0.0));
    if (-y.z <= 0.0) return false;
    vec2 q = to_window(y);
    if (!on_screen(q)) return false;
    ivec2 qi = ivec2(q);
    if (texelFetch(u_front, qi, 0).w > 0.5) return false;
    at = qi;
    return true;
}

// A skinned candidate: the fixed point of q = p - u D(q) on its own displacement.
bool walked(int id, float u, out float depth, out ivec2 at) {
    vec2 p = g_centre;
    for (int it = 0; it < 3; ++it) {
        ivec2 qi = ivec2(floor(p));
        if (!on_screen(p)) return false;
        vec4 f = texelFetch(u_front, qi, 0);
        float l = length(f.xy);
        if (l > u_max_disp) f.xy *= u_max_disp / l;
        vec2 land = vec2(qi) + 0.5 + u * f.xy - g_centre;
        if (int(f.w + 0.5) == id && max(abs(land.x), abs(land.y)) <= u_tolerance) {
            depth = f.z;
            at = qi;
            return true;
        }
        p = g_centre - u * f.xy;
    }
    return false;
}

// Candidate `id` of kind `kind` at exposure fraction f (locate(f) first): its surface on
// this pixel then, found at G-buffer pixel `at`, and its view depth then.
bool covers(int id, int kind, float f, float guess, out float depth, out ivec2 at) {
    if (kind == 2) return walked(id, f - 0.5, depth, at);
    return rigid(id, kind == 0, guess, depth, at);
}
