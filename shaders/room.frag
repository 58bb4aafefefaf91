#version 460
// Lambertian room lit by the ceiling area light, approximated as a point
// emitter at its centre (no shadows) plus an ambient term. This is the
// real-time approximation the static-EM baseline uses; the gold standard
// is the tracer's, and inferred textures replace this shading later.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 albedo;
    vec4 emission;
} pc;

layout(set = 0, binding = 0) uniform sampler2D albedo_texture;
// One branch-free formula for every light (llvmpipe runs both sides of a
// branch on a uniform, which cost the pass ~40%): a light at `position.xyz`
// (w = 1; an area light as a point emitter, or a point light) or a sun
// towards `position.xyz` (w = 0, unit, so d² = 1).
layout(set = 0, binding = 1, std140) uniform Light {
    vec4 position; // xyz; w = 1 (at a point) or 0 (a sun: unit direction towards it)
    vec4 normal;   // xyz the area light's unit normal, into the room; w = ambient scale
    vec4 radiance; // rgb radiance × area, intensity or irradiance; a = 1 for an area light
} light;

layout(location = 0) out vec4 out_color;

const float PI = 3.14159265358979;

void main() {
    // Untextured materials bind a white texel: no branch (llvmpipe would
    // run both sides).
    vec3 albedo = pc.albedo.rgb * texture(albedo_texture, in_uv).rgb;
    vec3 n = normalize(in_normal);
    vec3 to_light = light.position.xyz - in_position * light.position.w;
    float d2 = max(dot(to_light, to_light), 1e-6);
    vec3 l = to_light * inversesqrt(d2);
    float cos_surface = max(dot(n, l), 0.0);
    float cos_light = mix(1.0, max(dot(light.normal.xyz, -l), 0.0), light.radiance.a);
    vec3 irradiance = light.radiance.rgb * cos_surface * cos_light / d2;
    vec3 ambient = light.radiance.rgb * light.normal.w;
    out_color = vec4(pc.emission.rgb + albedo / PI * (irradiance + PI * ambient), 1.0);
}
