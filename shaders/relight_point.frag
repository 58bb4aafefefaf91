#version 460
#extension GL_GOOGLE_include_directive : require
#include "relight_common.glsl"
// Point light: per pixel L = S − P (P from the position panorama, the traced
// depth along the pixel's view ray), Σ C_i Y_i(L/|L|) · intensity / |L|².
// Y_i is evaluated here without trigonometry, the same form as
// `inference::relight::sh::eval` (the appendix's recurrence for Q_lm divided
// by sin^m θ, times Re/Im (L.x + i L.z)^m), where the paper used cube maps;
// the loops have constant bounds, so they unroll into registers.

// N_lm of the appendix (1/√2 folded in for m = 0), indexed l(l + 1) + |m|.
const float N[25] = float[25](
    0.282094792, 0.488602512, 0.488602512, 0.488602512, 0.182091405,
    0.364182810, 0.630783131, 0.364182810, 0.182091405, 0.039336239,
    0.096353715, 0.304697200, 0.746352665, 0.304697200, 0.096353715,
    0.039336239, 0.005960340, 0.016858388, 0.063078313, 0.267618617,
    0.846284375, 0.267618617, 0.063078313, 0.016858388, 0.005960340);

void main() {
    int k = int(pc.power.w);
    uint base = first_pair(k);
    // Y_i(L/|L|) for every i first (constant indices: registers), then the sum.
    float y[25];
    vec3 l = pc.light.xyz - texelFetch(positions, ivec2(gl_FragCoord.xy), 0).xyz;
    float d2 = max(dot(l, l), 1e-8);
    vec3 d = l * inversesqrt(d2);
    float re = 1.0;
    float im = 0.0;
    float pmm = 1.0;
    for (int m = 0; m < 5; m++) {
        if (m > 0) {
            float r = re * d.x - im * d.z;
            im = re * d.z + im * d.x;
            re = r;
            pmm *= 1.0 - 2.0 * float(m);
        }
        float prev = 0.0;
        float cur = pmm;
        for (int l = m; l < 5; l++) {
            if (l == m + 1) {
                prev = cur;
                cur = float(2 * m + 1) * d.y * pmm;
            } else if (l > m + 1) {
                float next = (float(2 * l - 1) * d.y * cur - float(l + m - 1) * prev) / float(l - m);
                prev = cur;
                cur = next;
            }
            int center = l * l + l;
            float n = N[center + m] * cur;
            if (m == 0) {
                y[center] = n;
            } else {
                y[center + m] = n * re;
                y[center - m] = n * im;
            }
        }
    }
    vec3 sum = vec3(0.0);
    for (int j = 0; j < 12; j++) {
        if (2 * j < k) {
            vec3 a, b;
            coefficient_pair(base, j, a, b);
            // The padding coefficient (odd k) is zero.
            sum += y[2 * j] * a + y[2 * j + 1] * b;
        }
    }
    if (k > 24) {
        vec3 a, b;
        coefficient_pair(base, 12, a, b);
        sum += y[24] * a;
    }
    out_color = vec4(sum * pc.power.rgb / d2, 1.0);
}
