#version 460
// T·F_T·G_T + R·F_R·G_R with layered shells: each exit ray reads its
// shells nearest first (layers of one cube-map array) and composites them
// front to back, each inner layer premultiplied "over" the ones behind;
// the outermost is opaque (its alpha is not read). With per-sample layer
// maps (BLEND = 1) each layer mixes two samples' maps, linearly by the
// eye's place between them, as glass_blend.frag mixes the one shell's.
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
    vec4 blend; // x: shells (1 to 3); y, z: the array element of layer 0
                // of the two samples; w: the weight of z's
} pc;

// 1 when the array holds per-sample layer maps (element = sample's base +
// layer); a constant, so the traced layers' pipeline reads each layer once.
layout(constant_id = 0) const int BLEND = 0;

layout(set = 0, binding = 0) uniform samplerCubeArray layers;

layout(location = 0) out vec4 out_color;

// The layer count is uniform, so every branch below is taken by all
// fragments alike (no local arrays: lavapipe spills them to memory).
vec4 layer(vec3 dir, float k) {
    vec4 a = texture(layers, vec4(dir, pc.blend.y + k));
    if (BLEND == 0) {
        return a;
    }
    return mix(a, texture(layers, vec4(dir, pc.blend.z + k)), pc.blend.w);
}

vec3 over(vec3 l0, vec3 l1, vec3 l2) {
    int n = int(pc.blend.x);
    vec4 s0 = layer(l0, 0.0);
    if (n < 2) {
        return s0.rgb;
    }
    vec4 s1 = layer(l1, 1.0);
    if (n < 3) {
        return s0.rgb + (1.0 - s0.a) * s1.rgb;
    }
    vec3 s2 = layer(l2, 2.0).rgb;
    return s0.rgb + (1.0 - s0.a) * (s1.rgb + (1.0 - s1.a) * s2);
}

void main() {
    vec3 t = over(in_lookup_t0, in_lookup_t1, in_lookup_t2);
    vec3 r = over(in_lookup_r0, in_lookup_r1, in_lookup_r2);
    out_color = vec4(in_weight_t * t + in_weight_r * r, 1.0);
}
