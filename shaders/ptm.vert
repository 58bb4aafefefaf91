#version 460
// A parameterized texture map pasted on the reflector's own texture
// coordinates: the whole appearance of one viewpoint sample.
layout(location = 0) in vec3 in_position;
layout(location = 2) in vec2 in_uv;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0_weight; // a = this pass's blend weight
    vec4 slot;      // x = array element of this sample's map
} pc;

layout(location = 0) out vec2 out_uv;

invariant gl_Position;

void main() {
    out_uv = in_uv;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
