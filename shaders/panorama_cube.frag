#version 460
// One face of the static EM's cube, level 0, from the relit cylindrical
// panorama (`--light-path`): the direction through this texel
// ((2s − 1)·sc + (2t − 1)·tc + ma, the specification's face table, as
// engine/src/cube.rs), then the panorama's texel along it — azimuth
// atan2(z, x) across, height y/|xz| on the unit cylinder down
// (inference::relight::Panorama::direction inverted). Directions steeper
// than the panorama reaches read its top or bottom row.

layout(push_constant) uniform Push {
    vec4 sc; // xyz face axes; sc.w = face size in texels
    vec4 tc;
    vec4 ma;
} pc;

layout(set = 0, binding = 0) uniform sampler2D panorama;

layout(location = 0) out vec4 out_color;

const float PI = 3.14159265358979;

void main() {
    vec2 st = gl_FragCoord.xy / pc.sc.w;
    vec3 d = (2.0 * st.x - 1.0) * pc.sc.xyz + (2.0 * st.y - 1.0) * pc.tc.xyz + pc.ma.xyz;
    vec2 size = vec2(textureSize(panorama, 0));
    float u = atan(d.z, d.x) / (2.0 * PI);
    float h = d.y / max(length(d.xz), 1e-6);
    float v = 0.5 - h * size.x / (2.0 * PI * size.y);
    v = clamp(v, 0.5 / size.y, 1.0 - 0.5 / size.y);
    out_color = vec4(textureLod(panorama, vec2(fract(u), v), 0.0).rgb, 1.0);
}
