#version 460
#extension GL_GOOGLE_include_directive : require
#include "rem_common.glsl"
// The current view's sphere map from its (up to) three source maps, per
// destination texel p_d in one full-screen pass: each source is read at
// g_mirror_inv(T_s^-1 T_d g_mirror(p_d)) with its barycentric weight, faded
// to (almost) nothing near its singularity (the direction straight behind
// it). rgb = sum of weight x radiance, alpha = sum of weight x coverage,
// which the reflector divides out. Per texel rather than per vertex of a
// tessellated disk: exact where the warp bends most, and one read per
// source and texel instead of three blended draws (README, REM).

layout(push_constant) uniform Push {
    vec4 rotation[3]; // quaternions T_s^-1 T_d, destination frame to source frame
    vec4 weight;      // xyz barycentric weights (0 for an absent source)
    vec4 layer;       // xyz source layers
    vec4 fade;        // x = cosine (to the singularity) where the fade reaches zero, y = where it starts;
                      // z = 1: warp by the normal (a diffuse reflector), not the mirror direction
} pc;

layout(set = 0, binding = 0) uniform sampler2DArray sources;

layout(location = 0) out vec4 out_color;

vec3 rotate(vec4 q, vec3 v) {
    return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

void main() {
    vec2 p = gl_FragCoord.xy / vec2(textureSize(sources, 0).xy);
    vec2 xy = 2.0 * p - 1.0;
    if (dot(xy, xy) > 1.0) {
        out_color = vec4(0.0); // outside the sphere map's disk
        return;
    }
    bool by_normal = pc.fade.z > 0.5;
    vec3 d_dest = by_normal ? vec3(xy, sqrt(max(1.0 - dot(xy, xy), 0.0))) : g_mirror(p);
    vec4 sum = vec4(0.0);
    for (int i = 0; i < 3; i++) {
        if (pc.weight[i] > 0.0) {
            vec3 d = rotate(pc.rotation[i], d_dest);
            // Mirror: -d.z is the cosine of the angle to the source's
            // singularity (straight behind it). Normal: the source sees the
            // normal edge-on at d.z = 0 and not at all below; it fades in
            // over the 60° above the rim.
            float fade = by_normal ? smoothstep(0.0, 0.5, d.z)
                                   : 1.0 - smoothstep(pc.fade.y, pc.fade.x, -d.z);
            vec2 uv = by_normal ? d.xy * 0.5 + 0.5 : g_mirror_inv(d);
            vec4 texel = textureLod(sources, vec3(uv, pc.layer[i]), 0.0);
            sum += pc.weight[i] * max(fade, 1e-3) * texel;
        }
    }
    out_color = sum;
}
