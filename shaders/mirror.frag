#version 460
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) in vec3 in_lookup;
layout(location = 1) in float in_cos;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0;
} pc;

layout(set = 0, binding = 0) uniform samplerCube environment;
layout(set = 0, binding = 1) uniform sampler1D fresnel_lut; // (1 - cos)^5 over cos in [0, 1]

layout(location = 0) out vec4 out_color;

void main() {
    // Texel i holds (1 - i/(N-1))^5: address texel centres so that cos = 0
    // and cos = 1 read the exact end values.
    float n = float(textureSize(fresnel_lut, 0));
    float u = (clamp(in_cos, 0.0, 1.0) * (n - 1.0) + 0.5) / n;
    float factor = texture(fresnel_lut, u).r;
    vec3 fresnel = schlick(pc.f0.rgb, factor);
    out_color = vec4(fresnel * texture(environment, in_lookup).rgb, 1.0);
}
