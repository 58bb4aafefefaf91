// Shared by every shader. Keep in step with engine/src/shader_interface.rs.

// Schlick's Fresnel from the (1 - cos)^5 factor read from the 1D LUT; the
// same formula as inference::fresnel::schlick_fresnel on the CPU.
vec3 schlick(vec3 f0, float one_minus_cos_pow5) {
    return f0 + (vec3(1.0) - f0) * one_minus_cos_pow5;
}
