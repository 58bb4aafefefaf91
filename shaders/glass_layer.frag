#version 460
// glass.frag reading one layer of the layered shells' cube-map array: the
// outermost, for lens triangles no inner layer reaches (their vertices'
// outermost lookups, from the layered stream); with per-sample layer maps
// (BLEND = 1) mixed from two samples' maps, as glass_layers.frag.
layout(location = 0) in vec3 in_weight_t;
layout(location = 1) in vec3 in_weight_r;
layout(location = 2) in vec3 in_lookup_t;
layout(location = 3) in vec3 in_lookup_r;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 blend; // x: shells; y, z: the array element of layer 0 of the
                // two samples; w: the weight of z's
} pc;

layout(constant_id = 0) const int BLEND = 0;

layout(set = 0, binding = 0) uniform samplerCubeArray layers;

layout(location = 0) out vec4 out_color;

vec3 outermost(vec3 dir) {
    float k = pc.blend.x - 1.0;
    vec3 a = texture(layers, vec4(dir, pc.blend.y + k)).rgb;
    if (BLEND == 0) {
        return a;
    }
    return mix(a, texture(layers, vec4(dir, pc.blend.z + k)).rgb, pc.blend.w);
}

void main() {
    vec3 t = outermost(in_lookup_t);
    vec3 r = outermost(in_lookup_r);
    out_color = vec4(in_weight_t * t + in_weight_r * r, 1.0);
}
