#version 460
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) in vec3 in_lookup;
layout(location = 1) in float in_cos;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0; // rgb Schlick F0; w = LOD bias (PEM maps; 0 for static EMs)
} pc;

layout(set = 0, binding = 0) uniform samplerCube environment;
layout(set = 0, binding = 1) uniform sampler1D fresnel_lut; // (1 - cos)^5 over cos in [0, 1]

layout(location = 0) out vec4 out_color;

void main() {
    float factor = fresnel_factor(fresnel_lut, in_cos);
    vec3 fresnel = schlick(pc.f0.rgb, factor);
    out_color = vec4(fresnel * texture(environment, in_lookup, pc.f0.w).rgb, 1.0);
}
