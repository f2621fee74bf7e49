#version 330 core
// Draws one pool texture into a destination rectangle with a visualisation chosen at run
// time (viewer/render/passes/debug_view.py). The same rules as viewer/io/visualize.py, on the GPU.
// SOURCE_TYPE (define): 0 float/normalised texture, SOURCE_UINT unsigned integer, SOURCE_INT
// signed integer; u_kind one of KIND_<NAME> (viewer/render/passes/debug_view.py view_defines).
#if SOURCE_TYPE == SOURCE_UINT
uniform usampler2D u_src;
#elif SOURCE_TYPE == SOURCE_INT
uniform isampler2D u_src;
#else
uniform sampler2D u_src;
#endif

uniform int u_kind;        // KIND_COLOUR, KIND_DEPTH, ...
uniform vec4 u_dest;       // destination rectangle in window pixels: x0, y0, width, height
uniform int u_channel;     // first component shown (velocity in .zw of a 4-channel tile)
uniform float u_gain;      // colour: multiplier; velocity, tiles, scalar: 1 / full-scale value
uniform vec2 u_log_range;  // depth: log of the nearest and farthest hit depth
uniform int u_tile;        // tiles: texels of the source per tile (grid lines); 1 = none
out vec4 out_color;

const float PI = 3.14159265358979;

vec4 fetch(ivec2 p) {
    return vec4(texelFetch(u_src, p, 0));
}

float srgb(float x) {
    x = isnan(x) ? 0.0 : clamp(x, 0.0, 1.0);   // +inf -> 1, -inf -> 0 (imageio.py)
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

// Hue = direction (GL axes), value = length * u_gain: visualize.colour_wheel.
vec3 wheel(vec2 v) {
    float hue = fract(atan(v.y, v.x) / (2.0 * PI) + 1.0);
    float val = clamp(length(v) * u_gain, 0.0, 1.0);
    vec3 k = mod(hue * 6.0 + vec3(5.0, 3.0, 1.0), 6.0);
    return val * (1.0 - clamp(min(k, 4.0 - k), 0.0, 1.0));
}

// Distinct colours per id, 0 black: visualize.id_colours (the low 24 bits of id * 2654435761).
vec3 id_colour(uint id) {
    if (id == 0u) return vec3(0.0);
    uint h = (id * 2654435761u) & 0xFFFFFFu;
    uvec3 c = (uvec3(h >> 16, h >> 8, h) & 255u) | 64u;
    return vec3(c) / 255.0;
}

void main() {
    ivec2 size = textureSize(u_src, 0);
    vec2 uv = (gl_FragCoord.xy - u_dest.xy) / u_dest.zw;
    ivec2 p = clamp(ivec2(floor(uv * vec2(size))), ivec2(0), size - 1);
    vec4 t = fetch(p);
    vec3 rgb;
    if (u_kind == KIND_COLOUR) {
        vec3 c = t.rgb * u_gain;
        rgb = vec3(srgb(c.r), srgb(c.g), srgb(c.b));
    } else if (u_kind == KIND_DEPTH) {
        float d = t.r;
        float span = max(u_log_range.y - u_log_range.x, 1e-6);
        float g = 1.0 - (log(max(d, 1e-6)) - u_log_range.x) / span;
        rgb = vec3(d < BACKGROUND_DEPTH * 0.5 ? clamp(g * 220.0 + 35.0, 0.0, 255.0) / 255.0 : 0.0);
    } else if (u_kind == KIND_NORMAL) {
        rgb = clamp(t.xyz * 0.5 + 0.5, 0.0, 1.0);
    } else if (u_kind == KIND_ID) {
        rgb = id_colour(uint(t.r));
    } else if (u_kind == KIND_VELOCITY || u_kind == KIND_TILES) {
        vec2 v = u_channel >= 2 ? t.zw : t.xy;
        rgb = wheel(v);
        if (u_kind == KIND_TILES && u_tile > 1) {
            // A dark line on each tile's left and bottom border, so tiles can be counted.
            vec2 texel = uv * vec2(size);
            vec2 px = u_dest.zw / vec2(size);            // window pixels per source texel
            vec2 edge = fract(texel) * px;
            // Only along an axis where a texel spans several pixels (a k x 1 strip has
            // rows one pixel high).
            bvec2 line = bvec2(px.x >= 4.0 && edge.x < 1.0, px.y >= 4.0 && edge.y < 1.0);
            if (any(line)) rgb = rgb * 0.5 + 0.1;
        }
    } else {
        float x = u_channel == 1 ? t.y : (u_channel == 2 ? t.z : (u_channel == 3 ? t.w : t.x));
        x = isnan(x) ? 0.0 : abs(x);
        rgb = vec3(clamp(x * u_gain, 0.0, 1.0));
    }
    out_color = vec4(rgb, 1.0);
}
