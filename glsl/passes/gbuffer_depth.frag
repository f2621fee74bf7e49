#version 330 core
// The static objects' kept depths (viewer/render/passes/static_raster.py) at the pixels whose
// static has a draw rank in [u_ranks.x, u_ranks.y), written through the depth test into a
// depth-only target: where those statics still hold the pixel at one float farther than
// their own depth, they take it back before the next mover is drawn.
uniform usampler2D u_rank;
uniform sampler2D u_depth;      // the raster's depth buffer (no comparison mode)
uniform uvec2 u_ranks;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint rank = texelFetch(u_rank, p, 0).r;
    if (rank < u_ranks.x || rank >= u_ranks.y) discard;
    gl_FragDepth = texelFetch(u_depth, p, 0).r;
}
