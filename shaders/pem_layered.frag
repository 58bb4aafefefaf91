#version 460
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
// Two layers of one viewpoint sample: Fresnel × (local over distant); the
// local map is premultiplied RGBA with coverage alpha (PEM paper §4). The
// multipass formulation: one such pass per blended sample.

layout(location = 0) in vec3 in_distant;
layout(location = 1) in float in_cos;
layout(location = 2) in vec3 in_local;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0_weight;
    vec4 slot; // x = array element of the maps; z = LOD bias
} pc;

layout(set = 0, binding = 0) uniform samplerCubeArray distant_em;
layout(set = 0, binding = 1) uniform samplerCubeArray local_em;
layout(set = 0, binding = 2) uniform sampler1D fresnel_lut;

layout(location = 0) out vec4 out_color;

void main() {
    vec3 fresnel = schlick(pc.f0_weight.rgb, fresnel_factor(fresnel_lut, in_cos));
    vec3 distant = texture(distant_em, vec4(in_distant, pc.slot.x), pc.slot.z).rgb;
    vec4 local = texture(local_em, vec4(in_local, pc.slot.x), pc.slot.z);
    out_color = vec4(fresnel * local_over_distant(local, distant), pc.f0_weight.a);
}
