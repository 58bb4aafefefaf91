#version 460
// glass.frag reading one layer of the layered shells' cube-map array: the
// outermost, for lens triangles no inner layer reaches (their vertices'
// outermost lookups, from the layered stream).
layout(location = 0) in vec3 in_weight_t;
layout(location = 1) in vec3 in_weight_r;
layout(location = 2) in vec3 in_lookup_t;
layout(location = 3) in vec3 in_lookup_r;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 blend; // y: the layer read
} pc;

layout(set = 0, binding = 0) uniform samplerCubeArray layers;

layout(location = 0) out vec4 out_color;

void main() {
    vec3 t = texture(layers, vec4(in_lookup_t, pc.blend.y)).rgb;
    vec3 r = texture(layers, vec4(in_lookup_r, pc.blend.y)).rgb;
    out_color = vec4(in_weight_t * t + in_weight_r * r, 1.0);
}
