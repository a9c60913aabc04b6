#version 300 es
// Picking pass: triangle index + 1 in RGBA8 (0 = background).
precision highp float;
flat in uint vFace;
out vec4 outColor;
void main() {
  uint id = vFace + 1u;
  outColor = vec4(float(id & 255u), float((id >> 8) & 255u), float((id >> 16) & 255u), float((id >> 24) & 255u)) / 255.0;
}
