#version 450
// Lit, instanced meshes for both eyes. With RHOT_MULTIVIEW the eye is gl_ViewIndex (one
// multiview pass draws both layers); without it the eye comes from a push constant (one pass per
// eye).
//
// Without RHOT_VERTEX_LIT the world normal and the linear colour go to mesh.frag, which lights
// each pixel, and the _SRGB target encodes. With RHOT_VERTEX_LIT the lighting and the sRGB
// encoding happen here, per vertex, and the encoded colour is interpolated into a _UNORM view of
// the same image (line.frag passes it through): on a CPU driver that halves the cost of a
// 1080 x 1200 frame (docs/PERFORMANCE.md). Flat faces come out the same either way; on curved
// ones the diffuse term is interpolated rather than evaluated per pixel (Gouraud shading).
#extension GL_GOOGLE_include_directive : require
#ifdef RHOT_MULTIVIEW
#extension GL_EXT_multiview : require
#endif

#include "srgb.glsl"

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

#ifdef RHOT_VERTEX_LIT
layout(location = 0) out vec4 out_color;  // sRGB-encoded
#else
layout(location = 0) out vec3 out_normal_world;
layout(location = 1) out vec4 out_color;  // linear
#endif

void main() {
#ifdef RHOT_MULTIVIEW
  uint eye = gl_ViewIndex;
#else
  uint eye = push.eye;
#endif
  mat4 world_from_local = mat4(in_model0, in_model1, in_model2, in_model3);
  mat3 normal_matrix = mat3(in_normal0.xyz, in_normal1.xyz, in_normal2.xyz);
  gl_Position = frame.clip_from_world[eye] * (world_from_local * vec4(in_position, 1.0));
#ifdef RHOT_VERTEX_LIT
  // The same Lambert term as mesh.frag.
  vec3 n = normalize(normal_matrix * in_normal);
  float diffuse = max(dot(n, -frame.light_dir_world.xyz), 0.0);
  vec3 lit = in_color.rgb * (frame.light_color.rgb * diffuse + vec3(frame.light_color.a));
  out_color = vec4(srgb_from_linear(lit), in_color.a);
#else
  out_normal_world = normal_matrix * in_normal;
  out_color = in_color;
#endif
}
