#version 460
// Relighting a panorama from its signed SH maps (Wong, Or, Fu; seed 001):
// colour = Σ_i C_i · Y_i(L). A directional light gives every pixel the same
// scalar weights Y_i(L₀) (push constants, computed on the CPU); a point light
// gives each pixel its own L = S − P (P from the position panorama, traced
// depth along the pixel's view ray) and the fall-off intensity / |L|².
// Y_i is evaluated here without trigonometry, the same form as
// `inference::relight::sh::eval` (the appendix's recurrence for Q_lm divided
// by sin^m θ, times Re/Im (L.x + i L.z)^m), where the paper used cube maps.

// 128 bytes, lavapipe's push-constant limit: Y_0..Y_23 in `weights`, Y_24 in
// light.w; the sign of power.w tells a point light (−k) from a directional (+k).
layout(push_constant) uniform Push {
    vec4 weights[6]; // Y_i(L₀) of a directional light, i < 24
    vec4 light;      // xyz point-light position; w = Y_24(L₀) (directional)
    vec4 power;      // rgb irradiance (directional) or intensity (point); w = ±k
} pc;

layout(set = 0, binding = 0) uniform sampler2DArray sh_maps; // layer i = C_i (rgb)
layout(set = 0, binding = 1) uniform sampler2D positions;    // xyz first hit

layout(location = 0) out vec4 out_color;

// N_lm of the appendix (1/√2 folded in for m = 0), indexed l(l + 1) + |m|.
const float N[25] = float[25](
    0.282094792, 0.488602512, 0.488602512, 0.488602512, 0.182091405,
    0.364182810, 0.630783131, 0.364182810, 0.182091405, 0.039336239,
    0.096353715, 0.304697200, 0.746352665, 0.304697200, 0.096353715,
    0.039336239, 0.005960340, 0.016858388, 0.063078313, 0.267618617,
    0.846284375, 0.267618617, 0.063078313, 0.016858388, 0.005960340);

void sh_basis(vec3 d, int bands, out float y[25]) {
    d = normalize(d);
    float re[5];
    float im[5];
    re[0] = 1.0;
    im[0] = 0.0;
    for (int m = 1; m < 5; m++) {
        re[m] = re[m - 1] * d.x - im[m - 1] * d.z;
        im[m] = re[m - 1] * d.z + im[m - 1] * d.x;
    }
    float pmm = 1.0;
    for (int m = 0; m < bands; m++) {
        if (m > 0) {
            pmm *= 1.0 - 2.0 * float(m);
        }
        float prev = 0.0;
        float cur = pmm;
        for (int l = m; l < bands; l++) {
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
                y[center + m] = n * re[m];
                y[center - m] = n * im[m];
            }
        }
    }
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int k = int(abs(pc.power.w));
    float y[25];
    vec3 scale = pc.power.rgb;
    if (pc.power.w < 0.0) {
        vec3 l = pc.light.xyz - texelFetch(positions, p, 0).xyz;
        float d2 = max(dot(l, l), 1e-8);
        int bands = int(round(sqrt(float(k))));
        sh_basis(l, bands, y);
        scale /= d2;
    } else {
        for (int i = 0; i < 24; i++) {
            y[i] = pc.weights[i / 4][i % 4];
        }
        y[24] = pc.light.w;
    }
    vec3 sum = vec3(0.0);
    for (int i = 0; i < k; i++) {
        sum += y[i] * texelFetch(sh_maps, ivec3(p, i), 0).rgb;
    }
    out_color = vec4(sum * scale, 1.0);
}
