#version 300 es
// Picking pass: triangles drawn unindexed (three vertices per triangle), so
// the triangle index is gl_VertexID / 3; it is written as a colour.
in vec3 aPosition;
uniform mat4 uViewProj;
flat out uint vFace;
void main() {
  vFace = uint(gl_VertexID / 3);
  gl_Position = uViewProj * vec4(aPosition, 1.0);
}
