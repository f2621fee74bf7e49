// Surface shading of docs/scene-format.md, shared by the raster G-buffer pass and the shading of
// ray-revealed surfaces, so both layers are lit identically.
// Needs MAX_LIGHTS, LIGHTS_TEXTURE, LIGHTS_PER_ROW and the texture kinds TEX_CHECKER,
// TEX_STRIPES, TEX_IMAGE defined (GpuScene.light_defines).

uniform vec3 u_ambient;
uniform int u_num_lights;
#if LIGHTS_TEXTURE
// More lights than the uniform storage holds (gpu_scene.light_slots): light k's direction
// at texel (2 (k % LIGHTS_PER_ROW), k / LIGHTS_PER_ROW), its colour beside it.
uniform sampler2D u_lights;
vec3 light_dir(int k) {
    return texelFetch(u_lights, ivec2(2 * (k % LIGHTS_PER_ROW), k / LIGHTS_PER_ROW), 0).xyz;
}
vec3 light_color(int k) {
    return texelFetch(u_lights, ivec2(2 * (k % LIGHTS_PER_ROW) + 1, k / LIGHTS_PER_ROW), 0).xyz;
}
#else
uniform vec3 u_light_dir[MAX_LIGHTS];      // direction the light travels (unit); MAX_LIGHTS
                                           // from gpu_scene.light_slots
uniform vec3 u_light_color[MAX_LIGHTS];
vec3 light_dir(int k) { return u_light_dir[k]; }
vec3 light_color(int k) { return u_light_color[k]; }
#endif

// The material: uniforms (GpuScene.bind_material), or with MATERIAL_PER_FRAGMENT globals
// that the includer sets before shade() (reveal_shade's object table). Not a struct: the
// G-buffer pass with its uniforms copied into one ran at half speed on llvmpipe.
#ifndef MATERIAL_PER_FRAGMENT
#define MATERIAL_PER_FRAGMENT 0
#endif
#if MATERIAL_PER_FRAGMENT
vec3 m_albedo;
float m_specular;
float m_shininess;
int m_tex_kind;
float m_tex_size;
int m_tex_axis;
vec3 m_albedo2;
#else
uniform vec3 u_albedo;
uniform float u_specular;
uniform float u_shininess;
uniform int u_tex_kind;                    // 0 none, or TEX_CHECKER, TEX_STRIPES, TEX_IMAGE
uniform float u_tex_size;
uniform int u_tex_axis;
uniform vec3 u_albedo2;
#define m_albedo u_albedo
#define m_specular u_specular
#define m_shininess u_shininess
#define m_tex_kind u_tex_kind
#define m_tex_size u_tex_size
#define m_tex_axis u_tex_axis
#define m_albedo2 u_albedo2
#endif
uniform sampler2D u_tex_image;             // linear RGB, repeat, bilinear

vec3 surface_albedo(vec3 p_local, vec2 uv) {
    if (m_tex_kind == TEX_CHECKER) {
        vec3 c = floor(p_local / m_tex_size);
        return mod(c.x + c.y + c.z, 2.0) == 0.0 ? m_albedo : m_albedo2;
    }
    if (m_tex_kind == TEX_STRIPES) {
        float c = floor(p_local[m_tex_axis] / m_tex_size);
        return mod(c, 2.0) == 0.0 ? m_albedo : m_albedo2;
    }
    if (m_tex_kind == TEX_IMAGE) {
        return texture(u_tex_image, uv).rgb;
    }
    return m_albedo;
}

// a / |a|, or 0 for a = 0 (normalize(0) is undefined in GLSL): a mesh's zero normal (a
// fold in a revolve profile, a face shared by both windings) then shades as ambient
// only on every driver, and the normal target holds 0, not NaN.
vec3 unit_or_zero(vec3 a) {
    return dot(a, a) > 0.0 ? normalize(a) : vec3(0.0);
}

// p_eye: the world position relative to the camera eye at the frame's time (the
// callers' transforms are composed so: GpuScene.object_matrices); n: world normal (any
// length).
vec3 shade(vec3 p_eye, vec3 n, vec3 p_local, vec2 uv) {
    n = unit_or_zero(n);
    vec3 v = normalize(-p_eye);
    if (dot(n, v) < 0.0) n = -n;                       // two-sided surfaces
    vec3 diffuse = u_ambient;
    vec3 spec = vec3(0.0);
    for (int k = 0; k < u_num_lights; ++k) {
        vec3 l = -light_dir(k);
        float ndl = max(0.0, dot(n, l));
        diffuse += ndl * light_color(k);
        // Skipped (exactly 0 anyway) where the material has no specular: pow is costly.
        if (ndl > 0.0 && m_specular > 0.0) {
            float ndh = max(0.0, dot(n, unit_or_zero(l + v)));
            // pow(0, 0) is undefined in GLSL; the contract's value is 1.
            float s = (m_shininess == 0.0) ? 1.0 : pow(ndh, m_shininess);
            spec += s * light_color(k);
        }
    }
    return surface_albedo(p_local, uv) * diffuse + m_specular * spec;
}
