#version 460
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
// One EM layer of one viewpoint sample, times Fresnel: the distant layer on
// the reflector's convex-hull triangles (they cannot see themselves), and
// the single map of a sphere-at-infinity PEM.

layout(location = 0) in vec3 in_distant;
layout(location = 1) in float in_cos;
layout(location = 2) in vec3 in_local;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0_weight;
    vec4 slot; // x = array element of the maps; z = LOD bias
} pc;

layout(set = 0, binding = 0) uniform samplerCubeArray distant_em;
layout(set = 0, binding = 1) uniform sampler1D fresnel_lut;

layout(location = 0) out vec4 out_color;

void main() {
    vec3 fresnel = schlick(pc.f0_weight.rgb, fresnel_factor(fresnel_lut, in_cos));
    out_color = vec4(fresnel * clamp_light(texture(distant_em, vec4(in_distant, pc.slot.x), pc.slot.z).rgb), pc.f0_weight.a);
}
