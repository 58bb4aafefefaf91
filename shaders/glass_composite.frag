#version 460
// Deferred glass, pass 2: each lens pixel shaded once from the G-buffer,
// as glass_blend.frag shades it: both exit rays read two per-sample shell
// maps (layers of one cube-map array) at the recorded level of detail,
// mixed by the eye's place between the samples.
layout(push_constant) uniform Push {
    mat4 view_proj; // unused here (shared with the G-buffer pass)
    vec4 blend;     // x, y: the two samples' array layers; z: the weight of y
} pc;

layout(set = 0, binding = 0) uniform sampler2D g_lookup_t;
layout(set = 0, binding = 1) uniform sampler2D g_lookup_r;
layout(set = 0, binding = 2) uniform sampler2D g_weight_t;
layout(set = 0, binding = 3) uniform sampler2D g_weight_r;
layout(set = 0, binding = 4) uniform samplerCubeArray shells;

layout(location = 0) out vec4 out_color;

vec3 shell(vec4 lookup) {
    vec3 a = textureLod(shells, vec4(lookup.xyz, pc.blend.x), lookup.w).rgb;
    vec3 b = textureLod(shells, vec4(lookup.xyz, pc.blend.y), lookup.w).rgb;
    return mix(a, b, pc.blend.z);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 t = texelFetch(g_weight_t, p, 0).rgb * shell(texelFetch(g_lookup_t, p, 0));
    vec3 r = texelFetch(g_weight_r, p, 0).rgb * shell(texelFetch(g_lookup_r, p, 0));
    out_color = vec4(t + r, 1.0);
}
