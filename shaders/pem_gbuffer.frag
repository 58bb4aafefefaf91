#version 460
// Deferred PEM compositing, pass 1: the reflector rasterized once into
// per-pixel lookup data — each layer's cube lookup with the level of detail
// a forward `texture()` with the reflector's LOD bias would use there
// (queried here, where the triangle's derivatives are: the unclamped level,
// `.y`, plus the bias as `texture(…, bias)` adds it, so the clamp to the
// map's levels comes after, in `textureLod`), and the Fresnel cosine. The stencil marks the pixels
// (set by the pipeline), so the compositing pass shades only those. Parts
// that see only the distant layer (convex-hull triangles) record no local
// lookup (LOD NO_LOCAL), so one compositing draw serves the whole reflector.

layout(location = 0) in vec3 in_distant;
layout(location = 1) in float in_cos;
layout(location = 2) in vec3 in_local;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0_weight;
    vec4 slot; // y = 1 when this part has a local layer; z = LOD bias
} pc;

const float NO_LOCAL = -1.0e4;

layout(set = 0, binding = 0) uniform samplerCubeArray distant_em;
layout(set = 0, binding = 1) uniform samplerCubeArray local_em;

layout(location = 0) out vec4 out_distant; // lookup, LOD
layout(location = 1) out vec4 out_local;   // lookup, LOD
layout(location = 2) out float out_cos;

void main() {
    out_distant = vec4(in_distant, textureQueryLod(distant_em, in_distant).y + pc.slot.z);
    out_local = pc.slot.y > 0.5 ? vec4(in_local, textureQueryLod(local_em, in_local).y + pc.slot.z)
                                : vec4(in_local, NO_LOCAL);
    out_cos = in_cos;
}
