// The sRGB transfer function (IEC 61966-2-1), linear [0, 1] to encoded [0, 1]: what an _SRGB
// render target applies on store. Used where the shaders write encoded colour into a _UNORM view
// themselves (vertex-lit shading, see mesh.vert).
vec3 srgb_from_linear(vec3 linear) {
  vec3 c = clamp(linear, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
