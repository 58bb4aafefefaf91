#version 460
// Diffuse room surfaces, emitters and (with the bare-pass push flag) any mesh.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 albedo;          // rgb; a = 1 when the texture modulates it
    vec4 emission;        // rgb emitted radiance
    vec4 pattern;         // rgb albedo × colors[1]; a = texel (albedo.glsl)
} pc;

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;

void main() {
    out_position = in_position;
    out_normal = in_normal;
    out_uv = in_uv;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
