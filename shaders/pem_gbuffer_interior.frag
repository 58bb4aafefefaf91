#version 460
// A reflector's inside in the G-buffer pass (reflector_interior.vert): no
// lookups and the cosine's "nothing drawn" sentinel (GBUFFER_CLEAR), the
// stencil left unmarked, so no compositing shades it and the room, drawn
// behind its depth, leaves the cleared black.
layout(location = 0) out vec4 out_distant;
layout(location = 1) out vec4 out_local;
layout(location = 2) out float out_cos;

void main() {
    out_distant = vec4(0.0);
    out_local = vec4(0.0);
    out_cos = -2.0;
}
