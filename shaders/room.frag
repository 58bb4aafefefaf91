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
// w of `center` says which light: > 0 the area light as a point emitter
// (w = its area), 0 an isotropic point light of intensity `radiance`, < 0 a
// sun of irradiance `radiance` towards `normal` (`--light-path`).
layout(set = 0, binding = 1, std140) uniform Light {
    vec4 center;   // xyz; w = area, 0 (point light) or < 0 (sun)
    vec4 normal;   // xyz unit, into the room (sun: towards it); w = ambient radiance scale
    vec4 radiance; // rgb
} light;

layout(location = 0) out vec4 out_color;

const float PI = 3.14159265358979;

void main() {
    vec3 albedo = pc.albedo.rgb;
    if (pc.albedo.a > 0.5) {
        albedo *= texture(albedo_texture, in_uv).rgb;
    }
    vec3 n = normalize(in_normal);
    vec3 irradiance;
    if (light.center.w < 0.0) {
        irradiance = light.radiance.rgb * max(dot(n, light.normal.xyz), 0.0);
    } else {
        vec3 to_light = light.center.xyz - in_position;
        float d2 = max(dot(to_light, to_light), 1e-6);
        vec3 l = to_light * inversesqrt(d2);
        float cos_surface = max(dot(n, l), 0.0);
        bool point = light.center.w == 0.0;
        float cos_light = point ? 1.0 : max(dot(light.normal.xyz, -l), 0.0);
        float area = point ? 1.0 : light.center.w;
        irradiance = light.radiance.rgb * area * cos_surface * cos_light / d2;
    }
    vec3 ambient = light.radiance.rgb * light.normal.w;
    out_color = vec4(pc.emission.rgb + albedo / PI * (irradiance + PI * ambient), 1.0);
}
