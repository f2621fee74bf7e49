#version 330 core
// Ray mask, step 1: the displacement test (ALGORITHMS.md 4.1-4.2), for a centred exposure.
// A moving pixel X of object I with displacement D is uncovered at shutter open if the
// point at X + D/2 lies off I, and at shutter close if X - D/2 does; it is kept when that
// probe sees a different object farther than X (by a relative threshold). Both ways.
// Where the camera moves the background moves too, and what X's background blur needs
// lies within half the RELATIVE displacement D - D_bg of the silhouette: the first probe
// that sees the background gives D_bg, and X +- (D - D_bg)/2 is tested as well.
// Outputs: the test's result and the relative displacement (D where no background was seen).
#include "raymask_common.glsl"
uniform sampler2D u_depth;
uniform usampler2D u_id;
uniform sampler2D u_velocity;
uniform float u_min_speed;          // px over the exposure
uniform float u_depth_threshold;    // relative
layout(location = 0) out uint out_mask;
layout(location = 1) out vec2 out_relative;

uint own_id;
float own_depth;

// Does the pixel at x + offset show another object farther than x? Its velocity in v.
bool uncovers(ivec2 x, vec2 offset, ivec2 size, out vec2 v) {
    ivec2 y = probe(x, offset, size);
    v = texelFetch(u_velocity, y, 0).xy;
    return texelFetch(u_id, y, 0).x != own_id
        && texelFetch(u_depth, y, 0).x > own_depth * (1.0 + u_depth_threshold);
}

void main() {
    ivec2 x = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(u_depth, 0);
    vec2 d = texelFetch(u_velocity, x, 0).xy;
    own_id = texelFetch(u_id, x, 0).x;
    own_depth = texelFetch(u_depth, x, 0).x;
    out_mask = 0u;
    out_relative = d;
    if (own_id == 0u || length(d) < u_min_speed) return;   // the sky hides nothing
    vec2 vb;
    bool found = false;
    for (int s = -1; s <= 1; s += 2) {
        if (uncovers(x, 0.5 * float(s) * d, size, vb)) {
            out_mask = 1u;
            if (!found) { out_relative = d - vb; found = true; }
        }
    }
    if (found) {
        for (int s = -1; s <= 1; s += 2) {
            if (uncovers(x, 0.5 * float(s) * out_relative, size, vb)) out_mask = 1u;
        }
    }
}
