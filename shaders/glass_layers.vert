#version 460
// glass.vert with layered shells (thesis §6.3): every vertex carries each
// exit ray's lookups into up to three shells, nearest first (a scene with
// fewer repeats its outermost shell; the fragment reads only its count).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_weight_t; // F_T·G_T: path starting by refraction
layout(location = 2) in vec3 in_weight_r; // F_R·G_R: path starting by reflection
layout(location = 3) in vec3 in_lookup_t0;
layout(location = 4) in vec3 in_lookup_t1;
layout(location = 5) in vec3 in_lookup_t2;
layout(location = 6) in vec3 in_lookup_r0;
layout(location = 7) in vec3 in_lookup_r1;
layout(location = 8) in vec3 in_lookup_r2;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 blend;
} pc;

layout(location = 0) out vec3 out_weight_t;
layout(location = 1) out vec3 out_weight_r;
layout(location = 2) out vec3 out_lookup_t0;
layout(location = 3) out vec3 out_lookup_t1;
layout(location = 4) out vec3 out_lookup_t2;
layout(location = 5) out vec3 out_lookup_r0;
layout(location = 6) out vec3 out_lookup_r1;
layout(location = 7) out vec3 out_lookup_r2;

void main() {
    out_weight_t = in_weight_t;
    out_weight_r = in_weight_r;
    out_lookup_t0 = in_lookup_t0;
    out_lookup_t1 = in_lookup_t1;
    out_lookup_t2 = in_lookup_t2;
    out_lookup_r0 = in_lookup_r0;
    out_lookup_r1 = in_lookup_r1;
    out_lookup_r2 = in_lookup_r2;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
