#version 460
#extension GL_GOOGLE_include_directive : require
#include "rem_common.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 eye;
    vec4 axis_x;
    vec4 axis_y;
    vec4 axis_z;
} pc;

// rgb = sum of weight x radiance, a = sum of weights.
layout(set = 0, binding = 0) uniform sampler2D blended;

layout(location = 0) out vec4 out_color;

void main() {
    vec3 n = normalize(in_normal);
    vec3 to_eye = normalize(pc.eye.xyz - in_position);
    if (dot(n, to_eye) < 0.0) {
        n = -n; // two-sided, as the tracer
    }
    // axis_x.w = 1: the maps are indexed by the normal (a diffuse
    // reflector), else by the mirror direction.
    vec3 d = pc.axis_x.w > 0.5 ? n : reflect(-to_eye, n);
    vec3 local = vec3(dot(d, pc.axis_x.xyz), dot(d, pc.axis_y.xyz), dot(d, pc.axis_z.xyz));
    vec2 uv = pc.axis_x.w > 0.5 ? local.xy * 0.5 + 0.5 : g_mirror_inv(local);
    vec4 sum = texture(blended, uv);
    out_color = vec4(sum.rgb / max(sum.a, 1e-6), 1.0);
}
