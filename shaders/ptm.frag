#version 460

layout(location = 0) in vec2 in_uv;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0_weight;
    vec4 slot;
} pc;

layout(set = 0, binding = 0) uniform sampler2DArray ptm;

layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(texture(ptm, vec3(in_uv, pc.slot.x)).rgb, pc.f0_weight.a);
}
