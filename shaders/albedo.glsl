// A diffuse surface's albedo as the room pass draws it. Procedural
// patterns (PATTERN 1 checker, 2 bricks, 3 grid) are filtered in closed
// form over the pixel's footprint (a tent per tile axis); 0 reads the
// bound texture. The same arithmetic, with its derivation and tests, is
// inference/src/scene/pattern_filter.rs. A specialization constant, not a
// push constant: llvmpipe runs every side of a branch it cannot fold.
layout(constant_id = 0) const int PATTERN = 0;

// The second antiderivative of pulses [k, k + h) of period 1.
float pulse_integral2(float x, float h) {
    float k = floor(x);
    float f = x - k;
    float partial = f < h ? 0.5 * f * f : h * f - 0.5 * h * h;
    return 0.5 * h * k * (k - 1.0) + k * (h - 0.5 * h * h) + k * h * f + partial;
}

// The average of the pulses around x under a tent of half-width a.
float pulse_filtered(float x, float a, float h) {
    float local = x - floor(x);
    float second = pulse_integral2(local + a, h) - 2.0 * pulse_integral2(local, h)
                 + pulse_integral2(local - a, h);
    return clamp(second / (a * a), 0.0, 1.0);
}

// The share of colors[1] under a tent of half-width w (tiles) centred on uv.
float pattern_weight(vec2 uv, vec2 w, float line_width) {
    if (PATTERN == 1) {
        float eu = pulse_filtered(uv.x, w.x, 0.5);
        float ev = pulse_filtered(uv.y, w.y, 0.5);
        return eu * (1.0 - ev) + ev * (1.0 - eu);
    }
    if (PATTERN == 2) {
        float wu = line_width;
        float wv = 2.0 * line_width;
        float across = pulse_filtered(4.0 * uv.y + wv, 4.0 * w.y, 2.0 * wv);
        float even = pulse_filtered(2.0 * uv.y, 2.0 * w.y, 0.5);
        float joint0 = pulse_filtered(2.0 * uv.x + wu, 2.0 * w.x, 2.0 * wu);
        float joint1 = pulse_filtered(2.0 * uv.x + 0.5 + wu, 2.0 * w.x, 2.0 * wu);
        float along = even * joint0 + (1.0 - even) * joint1;
        return across + (1.0 - across) * along;
    }
    float h = 0.5 * line_width;
    float fu = pulse_filtered(uv.x + h, w.x, line_width);
    float fv = pulse_filtered(uv.y + h, w.y, line_width);
    return 1.0 - (1.0 - fu) * (1.0 - fv);
}

// first: rgb albedo × colors[0] (or the albedo a texture modulates), a the
// line width; second: rgb albedo × colors[1], a the baked texel in tiles.
vec3 surface_albedo(sampler2D tex, vec2 uv, vec4 first, vec4 second) {
    if (PATTERN == 0) {
        return first.rgb * texture(tex, uv).rgb;
    }
    // The tent matched in variance to what the tracer averages: its
    // Gaussian film filter (sigma = 1/2 pixel) and the baked texels it
    // reads bilinearly (variance 1/4 texel^2); a tent's is half-width^2 / 6.
    vec2 dx = dFdx(uv);
    vec2 dy = dFdy(uv);
    vec2 w = sqrt(max(1.5 * (dx * dx + dy * dy + vec2(second.a * second.a)), vec2(1e-12)));
    return mix(first.rgb, second.rgb, pattern_weight(uv, w, first.a));
}
