#version 450
// Unlit lines for the ground grid and the debug-draw layer, for both eyes (see mesh.vert).
// With RHOT_ENCODE_SRGB the colour is sRGB-encoded here, for a _UNORM view of the target.
#extension GL_GOOGLE_include_directive : require
#ifdef RHOT_MULTIVIEW
#extension GL_EXT_multiview : require
#endif

#include "srgb.glsl"

layout(set = 0, binding = 0) uniform Frame {
  mat4 clip_from_world[2];
  vec4 light_dir_world;
  vec4 light_color;
} frame;

layout(push_constant) uniform Push {
  uint eye;
} push;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec4 in_color;

layout(location = 0) out vec4 out_color;

void main() {
#ifdef RHOT_MULTIVIEW
  uint eye = gl_ViewIndex;
#else
  uint eye = push.eye;
#endif
  gl_Position = frame.clip_from_world[eye] * vec4(in_position, 1.0);
#ifdef RHOT_ENCODE_SRGB
  out_color = vec4(srgb_from_linear(in_color.rgb), in_color.a);
#else
  out_color = in_color;
#endif
}
