#version 460
// A reflector shaded from parameterized environment maps. Both cube
// lookups and the Fresnel cosine come per vertex from CPU texgen (PEM
// paper: the reflected ray meets each layer's geometry on the CPU).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec4 in_distant; // xyz = distant-layer lookup (box), w = cos θ
layout(location = 2) in vec4 in_local;   // xyz = local-layer lookup (ellipsoid)

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0_weight; // rgb Schlick F0, a = this pass's blend weight
    vec4 slot;      // x = array element of this sample's maps
} pc;

layout(location = 0) out vec3 out_distant;
layout(location = 1) out float out_cos;
layout(location = 2) out vec3 out_local;

// The blend pass redraws the same triangles with LESS_OR_EQUAL: its depth
// must equal the first pass's bit for bit.
invariant gl_Position;

void main() {
    out_distant = in_distant.xyz;
    out_cos = in_distant.w;
    out_local = in_local.xyz;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
