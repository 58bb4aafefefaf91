#version 460
// glass.frag with per-sample shell maps: each exit ray reads two samples'
// maps (layers of one cube-map array) and mixes them by the eye's place
// between the samples; the mix is linear, like the maps' filtering.
layout(location = 0) in vec3 in_weight_t;
layout(location = 1) in vec3 in_weight_r;
layout(location = 2) in vec3 in_lookup_t;
layout(location = 3) in vec3 in_lookup_r;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 blend; // x, y: the two samples' array layers; z: the weight of y
} pc;

layout(set = 0, binding = 0) uniform samplerCubeArray shells;

layout(location = 0) out vec4 out_color;

vec3 shell(vec3 dir) {
    vec3 a = texture(shells, vec4(dir, pc.blend.x)).rgb;
    vec3 b = texture(shells, vec4(dir, pc.blend.y)).rgb;
    return mix(a, b, pc.blend.z);
}

void main() {
    out_color = vec4(in_weight_t * shell(in_lookup_t) + in_weight_r * shell(in_lookup_r), 1.0);
}
