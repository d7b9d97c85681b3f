#version 450
// Unlit lines for the ground grid and the debug-draw layer, for both eyes (see mesh.vert).
#ifdef RHOT_MULTIVIEW
#extension GL_EXT_multiview : require
#endif

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
  out_color = in_color;
}
