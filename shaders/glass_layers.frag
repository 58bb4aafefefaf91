#version 460
// T·F_T·G_T + R·F_R·G_R with layered shells: each exit ray reads its
// shells nearest first (layers of one cube-map array) and composites them
// front to back, each inner layer premultiplied "over" the ones behind;
// the outermost is opaque (its alpha is not read).
layout(location = 0) in vec3 in_weight_t;
layout(location = 1) in vec3 in_weight_r;
layout(location = 2) in vec3 in_lookup_t0;
layout(location = 3) in vec3 in_lookup_t1;
layout(location = 4) in vec3 in_lookup_t2;
layout(location = 5) in vec3 in_lookup_r0;
layout(location = 6) in vec3 in_lookup_r1;
layout(location = 7) in vec3 in_lookup_r2;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 blend; // x: shells (1 to 3)
} pc;

layout(set = 0, binding = 0) uniform samplerCubeArray layers;

layout(location = 0) out vec4 out_color;

// The layer count is uniform, so every branch below is taken by all
// fragments alike (no local arrays: lavapipe spills them to memory).
vec3 over(vec3 l0, vec3 l1, vec3 l2) {
    int n = int(pc.blend.x);
    vec4 s0 = texture(layers, vec4(l0, 0.0));
    if (n < 2) {
        return s0.rgb;
    }
    vec4 s1 = texture(layers, vec4(l1, 1.0));
    if (n < 3) {
        return s0.rgb + (1.0 - s0.a) * s1.rgb;
    }
    vec3 s2 = texture(layers, vec4(l2, 2.0)).rgb;
    return s0.rgb + (1.0 - s0.a) * (s1.rgb + (1.0 - s1.a) * s2);
}

void main() {
    vec3 t = over(in_lookup_t0, in_lookup_t1, in_lookup_t2);
    vec3 r = over(in_lookup_r0, in_lookup_r1, in_lookup_r2);
    out_color = vec4(in_weight_t * t + in_weight_r * r, 1.0);
}
