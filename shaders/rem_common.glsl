// Sphere maps of reflection-space IBR; the same functions as
// engine/src/rem/geometry.rs (g_mirror, g_mirror_inv), in each map's
// camera frame (z towards the viewer).

// The mirror reflection of the view (0, 0, 1) at sphere-map point p.
vec3 g_mirror(vec2 p) {
    vec2 xy = 2.0 * p - 1.0;
    float z = sqrt(max(1.0 - dot(xy, xy), 0.0));
    return vec3(2.0 * xy * z, 2.0 * z * z - 1.0);
}

// The sphere-map point whose mirror reflection is unit r (the rim for
// r = (0, 0, -1)).
vec2 g_mirror_inv(vec3 r) {
    vec3 h = r + vec3(0.0, 0.0, 1.0);
    float len = length(h);
    h = len > 1e-6 ? h / len : vec3(1.0, 0.0, 0.0);
    return h.xy * 0.5 + 0.5;
}
