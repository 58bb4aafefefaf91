#version 460
// The edge filter's tiles: one 4x4-pixel point per tile, at its centre in
// normalized device coordinates (computed on the CPU).
layout(location = 0) in vec2 centre;

void main() {
    gl_Position = vec4(centre, 0.0, 1.0);
    gl_PointSize = 4.0;
}
