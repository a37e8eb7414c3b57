#version 430 core
// `cpu` mode, first pass: the light-space position of the visible surface per pixel, read back
// and evaluated by the CPU (QueryAttenuation, the code of `pdsm query`). Alpha 1 marks a
// surface; the clear value 0 marks the background.

in vec3 position_light;
in vec3 normal_light;

layout(location = 0) out vec4 position_out;

void main() { position_out = vec4(position_light, 1.0); }
