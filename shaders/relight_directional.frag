#version 460
#extension GL_GOOGLE_include_directive : require
#include "relight_common.glsl"
// Directional light: every pixel the same scalar weights Y_i(L₀), computed
// on the CPU (`inference::relight::sh::eval`): a linear combination of maps.

void main() {
    int k = int(pc.power.w);
    uint base = first_pair(k);
    vec3 sum = vec3(0.0);
    for (int j = 0; j < 12; j++) {
        if (2 * j < k) {
            vec3 a, b;
            coefficient_pair(base, j, a, b);
            // Weights past k are zero (and so is the padding coefficient).
            sum += pc.weights[j / 2][(j % 2) * 2] * a + pc.weights[j / 2][(j % 2) * 2 + 1] * b;
        }
    }
    if (k > 24) {
        vec3 a, b;
        coefficient_pair(base, 12, a, b);
        sum += pc.light.w * a;
    }
    out_color = vec4(sum * pc.power.rgb, 1.0);
}
