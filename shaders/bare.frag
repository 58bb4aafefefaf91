#version 460
// The "bare pass": every mesh with one texture and nothing else. The
// static-EM frame is measured against it.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(set = 0, binding = 0) uniform sampler2D albedo_texture;

layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(texture(albedo_texture, in_uv).rgb, 1.0);
}
