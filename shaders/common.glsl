// Shared by every shader. Keep in step with engine/src/shader_interface.rs.

// Schlick's Fresnel from the (1 - cos)^5 factor read from the 1D LUT; the
// same formula as inference::fresnel::schlick_fresnel on the CPU.
vec3 schlick(vec3 f0, float one_minus_cos_pow5) {
    return f0 + (vec3(1.0) - f0) * one_minus_cos_pow5;
}

// The Schlick factor (1 - cos)^5 from the LUT: texel i holds
// (1 - i/(N-1))^5, so address texel centres to make cos = 0 and cos = 1
// read the exact end values.
float fresnel_factor(sampler1D lut, float cos_theta) {
    float n = float(textureSize(lut, 0));
    float u = (clamp(cos_theta, 0.0, 1.0) * (n - 1.0) + 0.5) / n;
    return texture(lut, u).r;
}

// Light read from an inferred map: a least-squares fit leaves some texels
// below zero (ringing beside sharp edges), which no traced light is, and a
// magnified read shows them as dark speckle. Clamped after the filtered
// read, as the local layer's coverage is (eval, whole frame: +0.13 to
// +0.17 dB on, between and above the orbit; README *No negative light*).
vec3 clamp_light(vec3 v) {
    return max(v, vec3(0.0));
}

// The local layer (premultiplied RGBA, coverage alpha) over the distant
// layer. Inferred coverage can stray outside [0, 1]; over needs it inside.
vec3 local_over_distant(vec4 local, vec3 distant) {
    return clamp_light(local.rgb) + (1.0 - clamp(local.a, 0.0, 1.0)) * clamp_light(distant);
}

// The alpha the deferred PEM composite writes: its pixels are the
// reflector's as the frame shows it (the room writes 1, a clear 0), which
// the edge filter reads back to find the reflector's outline.
const float REFLECTOR_ALPHA = 2.0;
