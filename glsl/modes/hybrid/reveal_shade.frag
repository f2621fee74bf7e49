#version 330 core
// The revealed layer, shaded exactly as the raster G-buffer shades (gbuffer.frag): the same
// shade() with the same GpuScene uniforms, the object's M(t) (relative to the eye) for
// position and normal, and its M at shutter open and close for the displacement, so the
// filter can blur it.
// Drawn over the tiles holding traced pixels (viewer/render/modes/hybrid/reveal.py), in draws
// of one or more revealed objects over their own tiles, each of whose pixels a draw
// writes: its record's key is one of the draw's (shaded), 0 (no ray: cleared), or -1
// (another draw writes it). The hit
// (face row, Embree u, v) is turned into mesh-space position, normal and uv here, from the
// face's three corners in u_faces, with the weights (1 - u - v, u, v).
// OBJECT_TABLE compiles the draw of several objects at once: each fragment takes its
// object's transforms and material from u_objects by the id in its record (llvmpipe
// charges ~0.1 ms a draw, whatever its size), and id 0, a ray that left the scene, gets
// the background colour as the G-buffer's background pass writes it. Without it the draw
// is one image-textured object's, from its uniforms (a draw samples one image). STATIC_LAYER compiles the draw of the rays whose hit is the
// first static surface along the pixel's primary ray (a still camera): that surface is
// what the raster of the static objects alone shows at the pixel, kept while the view
// holds (u_static_*), so it is copied, not shaded. The targets are packed for the composite
// (glsl/modes/hybrid/hybrid_layers.glsl): (D, depth, 1 + id) and (colour, 1); cleared ones hold 0,
// "nothing revealed here".
#define MATERIAL_PER_FRAGMENT OBJECT_TABLE
#include "passes/shading.glsl"
#include "passes/motion.glsl"

noperspective in vec2 v_record; // this pixel's hit record (glsl/passes/reveal_tiles.vert)
uniform sampler2D u_hits;       // (face row, u, v, 1 + object id); 0 where no ray
uniform sampler2D u_faces;      // TEXELS_PER_FACE per face, FACES_PER_ROW faces a row: corner
                                // c at 2c: (position, normal.x), at 2c + 1: (normal.yz, uv)
uniform mat4 u_view;
uniform vec3 u_background;
#if OBJECT_TABLE
uniform sampler2D u_objects;    // OBJECT_TEXELS per object id (hybrid/reveal.py ObjectTable):
                                // T(-eye) M(t), the modelviews at shutter open and close,
                                // the normal matrix, the material (OBJECT_<PART>: the
                                // first texel of each)
vec4 object_texel(int id, int k) {          // (OBJECTS_PER_ROW: a power of two)
    ivec2 at = ivec2((id % OBJECTS_PER_ROW) * OBJECT_TEXELS + k, id / OBJECTS_PER_ROW);
    return texelFetch(u_objects, at, 0);
}
mat4 object_mat4(int id, int k) {
    return mat4(object_texel(id, k), object_texel(id, k + 1), object_texel(id, k + 2),
                object_texel(id, k + 3));
}
#else
uniform mat4 u_model_eye;       // T(-eye(t)) M(t) (GpuScene.object_matrices)
uniform mat3 u_normal_matrix;
uniform uint u_object_id;
uniform ivec2 u_face_range;     // the faces this draw shades (a part's: its material)
#endif
#if SKINNED_FACES
uniform sampler2D u_faces_motion;   // as u_faces, per corner: (position at shutter open, 0),
                                    // (at close, 0): a skinned mesh's posed corners
#endif
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
#if OBJECT_TABLE
    int id = int(hit.w) - 1;            // the record's key, 1 + object id
    if (id == 0) {
        out_packed = vec4(0.0, 0.0, BACKGROUND_DEPTH, 1.0);     // id 0: the sky
        out_packed_color = vec4(u_background, 1.0);
        return;
    }
#endif
    float weight[3] = float[3](1.0 - hit.y - hit.z, hit.y, hit.z);
    int face = int(hit.x);
#if !OBJECT_TABLE
    if (face < u_face_range.x || face >= u_face_range.y) discard;   // another part's
#endif
    int row = face / FACES_PER_ROW;
    ivec2 base = ivec2((face - row * FACES_PER_ROW) * TEXELS_PER_FACE, row);
    vec3 local = vec3(0.0), normal_local = vec3(0.0);
    vec2 uv = vec2(0.0);
    for (int c = 0; c < 3; ++c) {
        vec4 a = texelFetch(u_faces, base + ivec2(2 * c, 0), 0);
        vec4 b = texelFetch(u_faces, base + ivec2(2 * c + 1, 0), 0);
        local += weight[c] * a.xyz;
        normal_local += weight[c] * vec3(a.w, b.xy);
        uv += weight[c] * b.zw;
    }
#if OBJECT_TABLE
    mat4 model = object_mat4(id, OBJECT_MODEL);
    mat4 modelview_open = object_mat4(id, OBJECT_OPEN);
    mat4 modelview_close = object_mat4(id, OBJECT_CLOSE);
    mat3 normal_matrix = mat3(object_texel(id, OBJECT_NORMAL).xyz,
                              object_texel(id, OBJECT_NORMAL + 1).xyz,
                              object_texel(id, OBJECT_NORMAL + 2).xyz);
    vec4 m0 = object_texel(id, OBJECT_MATERIAL), m1 = object_texel(id, OBJECT_MATERIAL + 1);
    vec4 m2 = object_texel(id, OBJECT_MATERIAL + 2);
    m_albedo = m0.rgb;
    m_specular = m0.a;
    m_albedo2 = m1.rgb;
    m_shininess = m1.a;
    m_tex_kind = int(m2.x);
    m_tex_size = m2.y;
    m_tex_axis = int(m2.z);
    float packed_id = hit.w;
#else
    mat4 model = u_model_eye, modelview_open = u_modelview_open, modelview_close = u_modelview_close;
    mat3 normal_matrix = u_normal_matrix;
    float packed_id = 1.0 + float(u_object_id);
#endif
    // (world positions relative to the eye: V = turn T(-eye), the eye is the origin)
    vec4 world = model * vec4(local, 1.0);
    vec4 view_now = vec4(mat3(u_view) * world.xyz, 1.0);
    vec3 n = unit_or_zero(normal_matrix * normal_local);
    if (dot(n, -world.xyz) < 0.0) n = -n;
    vec3 local_open = local, local_close = local;
#if SKINNED_FACES
    local_open = vec3(0.0);
    local_close = vec3(0.0);
    for (int c = 0; c < 3; ++c) {
        local_open += weight[c] * texelFetch(u_faces_motion, base + ivec2(2 * c, 0), 0).xyz;
        local_close += weight[c] * texelFetch(u_faces_motion, base + ivec2(2 * c + 1, 0), 0).xyz;
    }
#endif
    vec2 d = displacement_between(modelview_open * vec4(local_open, 1.0),
                                  modelview_close * vec4(local_close, 1.0), view_now);
    out_packed = vec4(d, -view_now.z, packed_id);
    out_packed_color = vec4(shade(world.xyz, n, local, uv), 1.0);
#endif
}
