#version 460
#extension GL_GOOGLE_include_directive : require
#include "rem_common.glsl"
// One source map warped to the current view in reflection space: a disk
// vertex at destination point p_d takes the texture coordinate
// g_mirror_inv(T_s^-1 T_d g_mirror(p_d)) in the source, and a weight that
// fades to (almost) nothing near the source's singularity, the direction
// straight behind it.
layout(location = 0) in vec2 in_point; // p_d in [0, 1]^2

layout(push_constant) uniform Push {
    mat4 dest_to_source; // upper 3x3: T_s^-1 T_d
    vec4 info; // x = barycentric weight, y = source layer, z = cos where the fade starts, w = cos where it ends
} pc;

layout(location = 0) out vec2 out_uv;
layout(location = 1) out float out_weight;

void main() {
    vec3 r_source = mat3(pc.dest_to_source) * g_mirror(in_point);
    out_uv = g_mirror_inv(r_source);
    // -r_source.z: cosine of the angle to the singularity.
    float fade = 1.0 - smoothstep(pc.info.w, pc.info.z, -r_source.z);
    out_weight = pc.info.x * max(fade, 1e-3);
    gl_Position = vec4(2.0 * in_point - 1.0, 0.0, 1.0);
}
