#version 460
// Adds weight x (source radiance, coverage) to the destination map; alpha
// accumulates the weights, which the reflector divides out.
layout(location = 0) in vec2 in_uv;
layout(location = 1) in float in_weight;

layout(push_constant) uniform Push {
    mat4 dest_to_source;
    vec4 info;
} pc;

layout(set = 0, binding = 0) uniform sampler2DArray sources;

layout(location = 0) out vec4 out_color;

void main() {
    vec4 texel = texture(sources, vec3(in_uv, pc.info.y));
    out_color = in_weight * texel;
}
