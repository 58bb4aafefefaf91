#version 460
#extension GL_GOOGLE_include_directive : require
// The room from inferred light maps: albedo (a scene file's pattern drawn
// in closed form, albedo.glsl; or texture × colour) times the object's
// light map — the traced light, solved from stacked views (soft shadows,
// indirect light, the light's true shape). No lighting maths: one texture
// read for a patterned surface. Emitters have no light map (a white texel
// is bound) and add their emission.
layout(location = 0) in vec2 in_uv;
layout(location = 1) in vec2 in_light_uv;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 albedo;
    vec4 emission;
    vec4 pattern;         // rgb albedo × colors[1]; a = texel (albedo.glsl)
} pc;

layout(set = 0, binding = 0) uniform sampler2D albedo_texture;
layout(set = 0, binding = 1) uniform sampler2D light_map;

layout(location = 0) out vec4 out_color;

#include "albedo.glsl"

void main() {
    // Untextured materials bind a white texel (PATTERN 0): no branch.
    vec3 albedo = surface_albedo(albedo_texture, in_uv, pc.albedo, pc.pattern);
    vec3 light = texture(light_map, in_light_uv).rgb;
    out_color = vec4(pc.emission.rgb + albedo * light, 1.0);
}
