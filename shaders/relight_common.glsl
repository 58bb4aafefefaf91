// Shared by relight_directional.frag and relight_point.frag: relighting a
// panorama from its signed SH maps (Wong, Or, Fu; seed 001), colour =
// Σ_i C_i · Y_i(L). Two shaders, not one with a branch, so each stays
// small: lavapipe runs the directional one at a few ops per coefficient.

// 128 bytes, lavapipe's push-constant limit: Y_0..Y_23 in `weights`, Y_24 in
// light.w (directional); power.w = k.
layout(push_constant) uniform Push {
    vec4 weights[6]; // Y_i(L₀) of a directional light, i < 24
    vec4 light;      // xyz point-light position; w = Y_24(L₀) (directional)
    vec4 power;      // rgb irradiance (directional) or intensity (point); w = k
} pc;

// Texel-major: the k coefficients of texel t side by side from t·s (s = k
// rounded up to even), each RGBA16F; read as pairs, one RGBA32UI texel per
// two coefficients (lavapipe gathers a texel fetch in unrolled code, a
// storage-buffer load lane by lane in a loop: the same bytes as a texel
// buffer cost less).
layout(set = 0, binding = 0) uniform usamplerBuffer pairs;
layout(set = 0, binding = 1) uniform sampler2D positions; // xyz first hit

layout(location = 0) out vec4 out_color;

// Coefficients 2j and 2j + 1 of the pixel whose first pair is `base`.
void coefficient_pair(uint base, int j, out vec3 a, out vec3 b) {
    uvec4 c = texelFetch(pairs, int(base) + j);
    a = vec3(unpackHalf2x16(c.x), unpackHalf2x16(c.y).x);
    b = vec3(unpackHalf2x16(c.z), unpackHalf2x16(c.w).x);
}

// Index of this pixel's first pair.
uint first_pair(int k) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    return uint(p.y * textureSize(positions, 0).x + p.x) * uint((k + 1) / 2);
}
