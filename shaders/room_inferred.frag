#version 460
// The room from inferred light maps: albedo (texture × colour, as in
// room.frag) times the object's light map — the traced light, solved from
// stacked views (soft shadows, indirect light, the light's true shape). No
// lighting maths: two texture reads. Emitters have no light map (a white
// texel is bound) and add their emission.
layout(location = 0) in vec2 in_uv;
layout(location = 1) in vec2 in_light_uv;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 albedo;
    vec4 emission;
} pc;

layout(set = 0, binding = 0) uniform sampler2D albedo_texture;
layout(set = 0, binding = 1) uniform sampler2D light_map;

layout(location = 0) out vec4 out_color;

void main() {
    // Untextured materials bind a white texel: no branch (llvmpipe would
    // run both sides).
    vec3 albedo = pc.albedo.rgb * texture(albedo_texture, in_uv).rgb;
    vec3 light = texture(light_map, in_light_uv).rgb;
    out_color = vec4(pc.emission.rgb + albedo * light, 1.0);
}
