#version 450
// Lit, instanced meshes for both eyes. Compiled twice: with RHOT_MULTIVIEW the eye is
// gl_ViewIndex (one multiview pass draws both layers); without it the eye comes from a push
// constant (one pass per eye).
#ifdef RHOT_MULTIVIEW
#extension GL_EXT_multiview : require
#endif

layout(set = 0, binding = 0) uniform Frame {
  mat4 clip_from_world[2];  // per eye: projection * eye_from_world
  vec4 light_dir_world;     // xyz: unit direction the light travels; w unused
  vec4 light_color;         // rgb: directional light; a: ambient strength
} frame;

layout(push_constant) uniform Push {
  uint eye;
} push;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
// Per instance: world_from_local (4 columns), the normal matrix (3 columns), colour.
layout(location = 2) in vec4 in_model0;
layout(location = 3) in vec4 in_model1;
layout(location = 4) in vec4 in_model2;
layout(location = 5) in vec4 in_model3;
layout(location = 6) in vec4 in_normal0;
layout(location = 7) in vec4 in_normal1;
layout(location = 8) in vec4 in_normal2;
layout(location = 9) in vec4 in_color;

layout(location = 0) out vec3 out_normal_world;
layout(location = 1) out vec4 out_color;

void main() {
#ifdef RHOT_MULTIVIEW
  uint eye = gl_ViewIndex;
#else
  uint eye = push.eye;
#endif
  mat4 world_from_local = mat4(in_model0, in_model1, in_model2, in_model3);
  mat3 normal_matrix = mat3(in_normal0.xyz, in_normal1.xyz, in_normal2.xyz);
  gl_Position = frame.clip_from_world[eye] * (world_from_local * vec4(in_position, 1.0));
  out_normal_world = normal_matrix * in_normal;
  out_color = in_color;
}
