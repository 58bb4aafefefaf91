#version 460
// Mirror reflector shaded from an environment map. The cube lookup vector
// and the Fresnel factor come per vertex from CPU texgen (binding 1), as
// in the PEM paper: the GPU never computes the reflection.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec4 in_texgen; // xyz = cube lookup, w = cos θ between normal and eye

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0; // rgb Schlick F0
} pc;

layout(location = 0) out vec3 out_lookup;
layout(location = 1) out float out_cos;

void main() {
    out_lookup = in_texgen.xyz;
    out_cos = in_texgen.w;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
