#version 450
// Lambert diffuse from one directional light plus an ambient term, in linear colour; the sRGB
// render target encodes the result.

layout(set = 0, binding = 0) uniform Frame {
  mat4 clip_from_world[2];
  vec4 light_dir_world;
  vec4 light_color;
} frame;

layout(location = 0) in vec3 in_normal_world;
layout(location = 1) in vec4 in_color;

layout(location = 0) out vec4 out_color;

void main() {
  vec3 n = normalize(in_normal_world);
  float diffuse = max(dot(n, -frame.light_dir_world.xyz), 0.0);
  vec3 lit = in_color.rgb * (frame.light_color.rgb * diffuse + vec3(frame.light_color.a));
  out_color = vec4(lit, in_color.a);
}
