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
    vec4 fade;        // x = cosine (to the singularity) where the fade reaches zero, y = where it starts
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
    vec3 r_dest = g_mirror(p);
    vec4 sum = vec4(0.0);
    for (int i = 0; i < 3; i++) {
        if (pc.weight[i] > 0.0) {
            vec3 r = rotate(pc.rotation[i], r_dest);
            // -r.z: cosine of the angle to the source's singularity.
            float fade = 1.0 - smoothstep(pc.fade.y, pc.fade.x, -r.z);
            vec4 texel = textureLod(sources, vec3(g_mirror_inv(r), pc.layer[i]), 0.0);
            sum += pc.weight[i] * max(fade, 1e-3) * texel;
        }
    }
    out_color = sum;
}
