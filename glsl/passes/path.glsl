// Each pixel's screen-space path over the exposure (viewer/render/passes/gbuffer.py PATH_TARGETS):
// SEGMENTS (2 or 4) linear pieces between the window positions at t_k = t - s/2 + k s/K,
// k = 0..K, each projected from V(t_k) M(t_k) per vertex and interpolated like the open
// and close positions of glsl/passes/motion.glsl. A point is stored as its offset (px, GL axes)
// from the surface's own window position at the frame time; the middle one, k = K/2, is
// that position itself (offset 0) and not stored: K offsets, two to an RGBA target
// (u_path0: k = 0, 1 (K = 4) or 0, 2 (K = 2); u_path1: k = 3, 4). The chord D, the
// G-buffer's displacement, is offset K - offset 0.
#define PATH_POINTS (SEGMENTS + 1)

// Path point k from stored slot j (slots skip the middle point).
int path_slot(int k) { return k < SEGMENTS / 2 ? k : k - 1; }

#ifdef PATH_READ
uniform sampler2D u_path0;
#if SEGMENTS == 4
uniform sampler2D u_path1;
#endif

// The K + 1 offsets of pixel p's path (a texture holding 0: a still or empty pixel).
void read_path(sampler2D t0,
#if SEGMENTS == 4
               sampler2D t1,
#endif
               ivec2 p, out vec2 o[PATH_POINTS]) {
    vec4 a = texelFetch(t0, p, 0);
#if SEGMENTS == 2
    o[0] = a.xy; o[1] = vec2(0.0); o[2] = a.zw;
#else
    vec4 b = texelFetch(t1, p, 0);
    o[0] = a.xy; o[1] = a.zw; o[2] = vec2(0.0); o[3] = b.xy; o[4] = b.zw;
#endif
}

void front_path_raw(ivec2 p, out vec2 o[PATH_POINTS]) {
#if SEGMENTS == 2
    read_path(u_path0, p, o);
#else
    read_path(u_path0, u_path1, p, o);
#endif
}

// Twice the farthest the surface goes from its frame-time position: |D| for a straight,
// uniform path; what tiles, dilation and the ray mask's speed test read for a path.
float path_extent(vec2 o[PATH_POINTS]) {
    float m = 0.0;
    for (int k = 0; k < PATH_POINTS; ++k) m = max(m, dot(o[k], o[k]));
    return 2.0 * sqrt(m);
}

// The offset at time u in [-1/2, 1/2] of the exposure: linear within each segment.
vec2 path_at(vec2 o[PATH_POINTS], float u) {
    float f = clamp((u + 0.5) * float(SEGMENTS), 0.0, float(SEGMENTS));
    int k = min(int(f), SEGMENTS - 1);
    return mix(o[k], o[k + 1], f - float(k));
}

// The path scaled about the frame-time position so that its extent is at most `limit`
// (the blur limit, as clamp_motion scales D).
void clamp_path(inout vec2 o[PATH_POINTS], float limit) {
    float e = path_extent(o);
    if (e > limit) {
        float s = limit / e;
        for (int k = 0; k < PATH_POINTS; ++k) o[k] *= s;
    }
}

// Read a path from one or two path targets whichever SEGMENTS is (the second unnamed at 2).
#if SEGMENTS == 2
#define READ_PATH(t0, t1, p, o) read_path(t0, p, o)
#else
#define READ_PATH(t0, t1, p, o) read_path(t0, t1, p, o)
#endif

// The segment (0..K-1) holding time u in [-1/2, 1/2] of the exposure.
int path_segment(float u) {
    return min(int(clamp((u + 0.5) * float(SEGMENTS), 0.0, float(SEGMENTS))), SEGMENTS - 1);
}

// The half vector a linear motion at segment s's speed would have over the whole
// exposure (K |o[s+1] - o[s]| / 2), clamped to [0.5, limit] px as the gathers clamp theirs:
// the per-segment radius of the post-process gathers' weights.
float piece_radius(vec2 o[PATH_POINTS], int s, float limit) {
    return clamp(0.5 * float(SEGMENTS) * length(o[s + 1] - o[s]), 0.5, limit);
}

// The path's dominant direction: its chord's, or where it comes back to its start (chord
// 0) its farthest point's; 0 for a still path.
vec2 path_direction(vec2 o[PATH_POINTS]) {
    vec2 c = o[SEGMENTS] - o[0];
    if (c != vec2(0.0)) return normalize(c);
    vec2 far = vec2(0.0);
    for (int k = 0; k < PATH_POINTS; ++k) if (dot(o[k], o[k]) > dot(far, far)) far = o[k];
    return far != vec2(0.0) ? normalize(far) : vec2(0.0);
}

// The gathers' neighbourhood path: the NeighborMax winner's, in u_tile_path0/1.
#ifdef PATH_TILES_READ
uniform sampler2D u_tile_path0;
#if SEGMENTS == 4
uniform sampler2D u_tile_path1;
#endif
void tile_path(ivec2 t, out vec2 o[PATH_POINTS]) { READ_PATH(u_tile_path0, u_tile_path1, t, o); }
#endif
#endif
