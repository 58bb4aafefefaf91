#version 460
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
// The tracer's film filter at the reflectors' silhouettes. Rasterization
// point-samples each pixel; the tracer averages its samples under a
// Gaussian of sigma 1/2 pixel, so where a pixel and one of its four
// neighbours differ in whether they show a reflector, the frame takes that
// Gaussian over the 3x3 pixels around it. Elsewhere (a flat region of
// the frame or of the reflector, already filtered by its textures) the
// pixel is left as it is.

// A copy of the frame around the reflectors' outlines (bilinear, clamped).
layout(set = 0, binding = 0) uniform sampler2D frame_copy;

layout(location = 0) out vec4 out_color;

// Whether the frame shows a reflector at p: the composite's alpha marks
// its pixels (not the G-buffer's coverage: an object the room pass draws
// in front of a reflector hides it).
bool covered(ivec2 p) {
    ivec2 last = textureSize(frame_copy, 0) - 1;
    return texelFetch(frame_copy, clamp(p, ivec2(0), last), 0).a > 0.5 * (1.0 + REFLECTOR_ALPHA);
}

// Per axis three taps (w, 1 - 2w, w) whose variance 2w is the film
// Gaussian's, 1/4 pixel squared: w = 1/8 (the Gaussian's own samples,
// w = 0.107, measured 0.01-0.02 dB lower over the frame). Two bilinear
// taps at +-2w pixels, weighted 1/2 each, give exactly that, so four taps
// give the separable 3x3.
const float TAP = 0.25;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    bool c = covered(p);
    if (covered(p + ivec2(1, 0)) == c && covered(p - ivec2(1, 0)) == c
            && covered(p + ivec2(0, 1)) == c && covered(p - ivec2(0, 1)) == c) {
        discard;
    }
    vec2 texel = 1.0 / vec2(textureSize(frame_copy, 0));
    vec2 at = gl_FragCoord.xy;
    vec3 sum = texture(frame_copy, (at + vec2(-TAP, -TAP)) * texel).rgb
        + texture(frame_copy, (at + vec2(TAP, -TAP)) * texel).rgb
        + texture(frame_copy, (at + vec2(-TAP, TAP)) * texel).rgb
        + texture(frame_copy, (at + vec2(TAP, TAP)) * texel).rgb;
    // The pixel keeps its own mark: the filter changes colours only.
    out_color = vec4(0.25 * sum, texelFetch(frame_copy, p, 0).a);
}
