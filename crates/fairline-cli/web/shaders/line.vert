#version 300 es
// Overlays (exact polylines, irregular stretches, wireframe, region):
// positions relative to the document centre.
in vec3 aPosition;
uniform mat4 uViewProj;
void main() {
  gl_Position = uViewProj * vec4(aPosition, 1.0);
}
