#version 460
// The room from inferred light maps: room.vert plus each vertex's place
// in its object's light map (a second vertex stream).
layout(location = 0) in vec3 in_position;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec2 in_light_uv;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 albedo;          // rgb; a = 1 when the texture modulates it
    vec4 emission;        // rgb emitted radiance
    vec4 pattern;         // rgb albedo × colors[1]; a = texel (albedo.glsl)
} pc;

layout(location = 0) out vec2 out_uv;
layout(location = 1) out vec2 out_light_uv;

void main() {
    out_uv = in_uv;
    out_light_uv = in_light_uv;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
