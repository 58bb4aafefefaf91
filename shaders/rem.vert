#version 460
// The reflector shaded from the blended radiance sphere map (per pixel).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 eye; // xyz world eye
    vec4 axis_x; // the destination map's frame (world), x right
    vec4 axis_y; // y up
    vec4 axis_z; // z towards the eye
} pc;

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;

void main() {
    out_position = in_position;
    out_normal = in_normal;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
