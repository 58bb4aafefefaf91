#version 460
// A reflector's inside (reflector_interior.vert): black, as the tracer's
// closed, unlit inside reads (0-2 of 255 on the teapot's lid gap).
layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(0.0, 0.0, 0.0, 1.0);
}
