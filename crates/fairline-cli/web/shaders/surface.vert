#version 300 es
// Surface pass: model-space position P (relative to the document centre)
// and the library's vertex normal N (Yong et al. Eq. (3)) are passed on
// unchanged; all highlight evaluation happens per fragment.
in vec3 aPosition;
in vec3 aNormal;
in float aScalar;
uniform mat4 uViewProj;
out vec3 vPos;
out vec3 vNormal;
out float vScalar;
void main() {
  vPos = aPosition;
  vNormal = aNormal;
  vScalar = aScalar;
  gl_Position = uViewProj * vec4(aPosition, 1.0);
}
