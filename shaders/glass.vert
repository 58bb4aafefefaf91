#version 460
// Glass by hybrid rendering (Hakura's thesis ch. 6): every vertex of the
// adaptively tessellated lens carries, from CPU ray paths through the
// glass, the two greedy paths' weights F·G (per channel) and their exit
// rays' lookups into the shell map. The GPU interpolates them only.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_weight_t; // F_T·G_T: path starting by refraction
layout(location = 2) in vec3 in_weight_r; // F_R·G_R: path starting by reflection
layout(location = 3) in vec3 in_lookup_t;
layout(location = 4) in vec3 in_lookup_r;

layout(push_constant) uniform Push {
    mat4 view_proj;
} pc;

layout(location = 0) out vec3 out_weight_t;
layout(location = 1) out vec3 out_weight_r;
layout(location = 2) out vec3 out_lookup_t;
layout(location = 3) out vec3 out_lookup_r;

void main() {
    out_weight_t = in_weight_t;
    out_weight_r = in_weight_r;
    out_lookup_t = in_lookup_t;
    out_lookup_r = in_lookup_r;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
