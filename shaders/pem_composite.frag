#version 460
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
// Deferred PEM compositing, pass 2: each covered pixel shaded once, reading
// every layer of every blended viewpoint sample at the level of detail the
// G-buffer recorded: Fresnel × Σ_s w_s (local_s over distant_s).

layout(push_constant) uniform Push {
    vec4 f0;     // rgb Schlick F0
    vec4 weight; // weights of up to 4 samples (sum 1)
    vec4 slot;   // array element of each sample's maps
    vec4 info;   // x = samples (= SAMPLES), y = 1 when the reflector has a local layer
} pc;

// How many samples this pipeline variant blends (1 to 4). A constant, not
// the push constant: lavapipe executes the body of every loop iteration or
// branch the shader holds, taken or not, so a variant compiles only the
// lookups it reads (README "PEM playback: speed").
layout(constant_id = 0) const int SAMPLES = 4;

layout(set = 0, binding = 0) uniform sampler2D g_distant;
layout(set = 0, binding = 1) uniform sampler2D g_local;
layout(set = 0, binding = 2) uniform sampler2D g_cos;
layout(set = 0, binding = 3) uniform samplerCubeArray distant_em;
layout(set = 0, binding = 4) uniform samplerCubeArray local_em;
layout(set = 0, binding = 5) uniform sampler1D fresnel_lut;

layout(location = 0) out vec4 out_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 d = texelFetch(g_distant, p, 0);
    vec4 l = texelFetch(g_local, p, 0);
    float cos_theta = texelFetch(g_cos, p, 0).r;
    // The G-buffer marks parts without a local layer by a huge negative LOD.
    bool local_layer = pc.info.y > 0.5 && l.w > -1.0e3;
    vec3 sum = vec3(0.0);
    for (int s = 0; s < SAMPLES; s++) {
        vec3 distant = textureLod(distant_em, vec4(d.xyz, pc.slot[s]), d.w).rgb;
        vec3 c = clamp_light(distant);
        if (local_layer) {
            vec4 local = textureLod(local_em, vec4(l.xyz, pc.slot[s]), l.w);
            c = local_over_distant(local, distant);
        }
        sum += pc.weight[s] * c;
    }
    float n = float(textureSize(fresnel_lut, 0));
    float u = (clamp(cos_theta, 0.0, 1.0) * (n - 1.0) + 0.5) / n;
    vec3 fresnel = schlick(pc.f0.rgb, textureLod(fresnel_lut, u, 0.0).r);
    out_color = vec4(fresnel * sum, REFLECTOR_ALPHA);
}
