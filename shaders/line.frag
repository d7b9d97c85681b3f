#version 450
// Passes the interpolated colour through: lines, and meshes lit per vertex (mesh.vert).
layout(location = 0) in vec4 in_color;
layout(location = 0) out vec4 out_color;
void main() { out_color = in_color; }
