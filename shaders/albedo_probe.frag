#version 460
#extension GL_GOOGLE_include_directive : require
// A diffuse surface's albedo alone, exactly as the room passes draw it:
// the known factor of the light-map solve (compile/room/solve.rs).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 albedo;
    vec4 emission;
    vec4 pattern;
} pc;

layout(set = 0, binding = 0) uniform sampler2D albedo_texture;

layout(location = 0) out vec4 out_color;

#include "albedo.glsl"

void main() {
    out_color = vec4(surface_albedo(albedo_texture, in_uv, pc.albedo, pc.pattern), 1.0);
}
