#version 460
// Deferred glass, pass 1: the lens rasterized once into per-pixel lookup
// data — both paths' exit-ray lookups, each with the level of detail a
// forward `texture()` would use there (queried here, where the triangle's
// derivatives are: the unclamped level `.y`; `textureLod` clamps it to the
// maps' levels), and both paths' weights F·G. The stencil marks the pixels
// (set by the pipeline), so the composite shades each of them once however
// many 2×2 quads of small triangles covered it.
layout(location = 0) in vec3 in_weight_t;
layout(location = 1) in vec3 in_weight_r;
layout(location = 2) in vec3 in_lookup_t;
layout(location = 3) in vec3 in_lookup_r;

layout(set = 0, binding = 0) uniform samplerCubeArray shells;

layout(location = 0) out vec4 out_lookup_t; // lookup, LOD
layout(location = 1) out vec4 out_lookup_r; // lookup, LOD
layout(location = 2) out vec4 out_weight_t;
layout(location = 3) out vec4 out_weight_r;

void main() {
    out_lookup_t = vec4(in_lookup_t, textureQueryLod(shells, in_lookup_t).y);
    out_lookup_r = vec4(in_lookup_r, textureQueryLod(shells, in_lookup_r).y);
    out_weight_t = vec4(in_weight_t, 0.0);
    out_weight_r = vec4(in_weight_r, 0.0);
}
