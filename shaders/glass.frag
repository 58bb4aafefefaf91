#version 460
// T·F_T·G_T + R·F_R·G_R: the shell map read along both exit rays.
layout(location = 0) in vec3 in_weight_t;
layout(location = 1) in vec3 in_weight_r;
layout(location = 2) in vec3 in_lookup_t;
layout(location = 3) in vec3 in_lookup_r;

layout(push_constant) uniform Push {
    mat4 view_proj;
} pc;

layout(set = 0, binding = 0) uniform samplerCube shell;

layout(location = 0) out vec4 out_color;

void main() {
    vec3 t = texture(shell, in_lookup_t).rgb;
    vec3 r = texture(shell, in_lookup_r).rgb;
    out_color = vec4(in_weight_t * t + in_weight_r * r, 1.0);
}
