#version 430 core
// Every viewer pass draws in the PDSM's light space (origin at the light centre, z along the
// light normal): the baked scene is uploaded there already (computed in double on the CPU,
// then rounded to float), dynamic objects are placed by light_from_object.

layout(location = 0) in vec3 position_object;
layout(location = 1) in vec3 normal_object;
layout(location = 2) in vec2 texture_uv_in;  // receivers with a shadowmask texture; else (0, 0)

uniform mat4 light_from_object;   // identity for the baked scene
uniform mat3 normal_from_object;  // inverse transpose of its upper 3x3
uniform mat4 clip_from_light;     // the camera, or a shadow map's projection

out vec3 position_light;
out vec3 normal_light;
out vec2 texture_uv;

void main() {
  vec4 p = light_from_object * vec4(position_object, 1.0);
  position_light = p.xyz;
  normal_light = normal_from_object * normal_object;
  texture_uv = texture_uv_in;
  gl_Position = clip_from_light * p;
}
