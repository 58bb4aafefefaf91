#version 460
// A reflector's inside, where the eye looks between its parts (the gap
// between a teapot's lid and body): the caps over its openings
// (inference::caps), drawn with depth, both sides. Without them culled
// back faces showed the room through the object where the tracer sees the
// unlit inside. Position only; the push block is pem.vert's.
layout(location = 0) in vec3 in_position;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 f0_weight;
    vec4 slot;
} pc;

invariant gl_Position;

void main() {
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
