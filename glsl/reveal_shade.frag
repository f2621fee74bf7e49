#version 330 core
// The revealed layer, shaded exactly as the raster G-buffer shades (gbuffer.frag): the same
// shade() with the same GpuScene uniforms, the object's M(t) for position and normal, and
// its M at shutter open and close for the displacement, so the filter can blur it.
// Drawn over the tiles holding traced pixels (viewer/render/reveal_pass.py), once per
// revealed object over its own tiles, each of whose pixels it writes: its record's
// key is this object's (shaded), 0 (no ray: cleared), or -1 (another object's draw
// writes it). The hit
// (face row, Embree u, v) is turned into mesh-space position, normal and uv here, from the
// face's three corners in u_faces, with the weights (1 - u - v, u, v).
// u_miss draws the rays that left the scene: the background colour, as the G-buffer's
// background pass writes it. STATIC_LAYER compiles the draw of the rays whose hit is the
// first static surface along the pixel's primary ray (a still camera): that surface is
// what the raster of the static objects alone shows at the pixel, kept while the view
// holds (u_static_*), so it is copied, not shaded. The targets are packed for the composite
// (glsl/hybrid_layers.glsl): (D, depth, 1 + id) and (colour, 1); cleared ones hold 0,
// "nothing revealed here".
#include "shading.glsl"
#include "motion.glsl"

noperspective in vec2 v_record; // this pixel's hit record (glsl/reveal_tiles.vert)
uniform sampler2D u_hits;       // (face row, u, v, 1 + object id); 0 where no ray
uniform sampler2D u_faces;      // 6 texels per face, FACES_PER_ROW faces a row: corner c at
                                // 2c: (position, normal.x), at 2c + 1: (normal.yz, uv)
uniform mat4 u_model;
uniform mat4 u_view;
uniform mat3 u_normal_matrix;
uniform vec3 u_eye;
uniform uint u_object_id;
uniform bool u_miss;
uniform vec3 u_background;
#if STATIC_LAYER
uniform sampler2D u_static_front;   // the static objects' raster: (D, depth, id), colour
uniform sampler2D u_static_color;
#endif

layout(location = 0) out vec4 out_packed;
layout(location = 1) out vec4 out_packed_color;


void main() {
    vec4 hit = texelFetch(u_hits, ivec2(floor(v_record)), 0);
    if (hit.w < 0.0) discard;               // another object's draw writes this pixel
    if (hit.w == 0.0) {                     // no ray here: "nothing revealed"
        out_packed = vec4(0.0);
        out_packed_color = vec4(0.0);
        return;
    }
#if STATIC_LAYER
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 f = texelFetch(u_static_front, p, 0);
    out_packed = vec4(f.xyz, f.w + 1.0);
    out_packed_color = vec4(texelFetch(u_static_color, p, 0).rgb, 1.0);
#else
    if (u_miss) {
        out_packed = vec4(0.0, 0.0, BACKGROUND_DEPTH, 1.0);     // id 0: the sky
        out_packed_color = vec4(u_background, 1.0);
        return;
    }
    float weight[3] = float[3](1.0 - hit.y - hit.z, hit.y, hit.z);
    int face = int(hit.x);
    int row = face / FACES_PER_ROW;
    ivec2 base = ivec2((face - row * FACES_PER_ROW) * 6, row);
    vec3 local = vec3(0.0), normal_local = vec3(0.0);
    vec2 uv = vec2(0.0);
    for (int c = 0; c < 3; ++c) {
        vec4 a = texelFetch(u_faces, base + ivec2(2 * c, 0), 0);
        vec4 b = texelFetch(u_faces, base + ivec2(2 * c + 1, 0), 0);
        local += weight[c] * a.xyz;
        normal_local += weight[c] * vec3(a.w, b.xy);
        uv += weight[c] * b.zw;
    }
    vec4 world = u_model * vec4(local, 1.0);
    vec4 view_now = u_view * world;
    vec3 n = normalize(u_normal_matrix * normal_local);
    if (dot(n, u_eye - world.xyz) < 0.0) n = -n;
    out_packed = vec4(exposure_displacement(local, view_now), -view_now.z,
                      1.0 + float(u_object_id));
    out_packed_color = vec4(shade(world.xyz, n, local, uv, u_eye), 1.0);
#endif
}
