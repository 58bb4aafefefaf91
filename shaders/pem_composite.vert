#version 460
// One triangle covering the screen; the render area and the stencil limit
// it to a reflector's pixels.
void main() {
    vec2 p = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
