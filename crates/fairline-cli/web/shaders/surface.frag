#version 300 es
// Exact per-fragment highlight shading.
//
// Linear light array (Yong et al. Eq. (1) as corrected in DESIGN.md §3):
//   d = ((P − A0) × N)·H / (Z·N),
// with N the interpolated, renormalised vertex normal and P the fragment's
// model-space position; no line where |Z·N| < minimum cosine of the model.
// Light m lies at d = m·s; a line is drawn where |d − m·s| is below
// uLineWidth pixels (fwidth(d)), a band where it is below the band
// half-width.
//
// Circular lights (Nishiyama et al. §2): the signed distance d_s of
// Eq. (2.18) between the normal line P + τN and the circle
// L(θ) = C + R(cos θ n + sin θ b). The closest approach is a stationary
// point of g(θ) = |(L(θ) − P) − ((L(θ) − P)·N)N|², whose stationary points
// are exactly the real roots of the quartic Eq. (2.15)–(2.16); it is found
// here as the global minimum of g over uThetaSamples (48) samples of θ,
// polished by the
// Newton steps of the library (g is a trigonometric polynomial of degree 2,
// at most 4 stationary points, so the samples bracket the global minimum).
// d_s = d·(N × L̇)/|N × L̇|, L̇ of Eq. (2.17).
//
// Isophotes: lines of constant N·Z (angle steps of uSpacing degrees).
//
// Reflection zebra (as Rhino's Zebra and Alias' diagnostic shading): the
// eye's ray reflected at the fragment, R = reflect(−V, N), looks up an
// environment of parallel tube lights at infinity along H: the stripe is
// the angle of R around H, atan2(R·(H × Z), R·Z), in steps of uSpacing
// degrees, dark over the band fraction 2·uBandHalf of each step. The
// stripes move with the eye, unlike the lines of the light array.
// Every stripe pattern fades to its mean where its period on the screen
// falls below about three pixels (fwidth), never to speckle.
precision highp float;
in vec3 vPos;
in vec3 vNormal;
in float vScalar;
uniform int uMode;            // 0 plain, 1 lines, 2 bands, 3 isophotes, 4 circular lines, 5 circular bands, 6 reflection zebra
uniform vec3 uA0;             // light 0 point, relative to the document centre
uniform vec3 uZ;              // plane normal (unit)
uniform vec3 uH;              // light direction (unit, orthogonal to Z)
uniform float uSpacing;       // s
uniform float uBandHalf;      // band half-width (model units)
uniform float uMinCos;        // the model's minimum |Z·N|
uniform float uLineWidth;     // pixels
uniform vec3 uCircleCenter;   // relative to the document centre
uniform vec3 uCircleN;
uniform vec3 uCircleB;
uniform float uRadii[16];
uniform int uRadiusCount;
// 48 (viewer.js). Loop bounds are uniforms, not constants, so that the
// compiler keeps the loops: unrolled (16 radii × 48 samples) the shader took
// seconds to compile in software GL, the largest part of the first frame.
uniform int uThetaSamples;
uniform vec3 uEye;            // eye position, model space
uniform int uScalarOn;
uniform float uScalarLo;
uniform float uScalarHi;
uniform sampler2D uColormap;
uniform vec3 uBaseColor;
out vec4 outColor;

const float PI = 3.14159265358979;

// signed distance of Eq. (2.18) to the circle of radius r; valid = false
// where it is undefined (N parallel to L̇).
float circleDistance(vec3 p, vec3 n, float r, out bool valid) {
  float best = 1e30;
  float bc = 1.0, bs = 0.0;
  float dth = 2.0 * PI / float(max(uThetaSamples, 1));
  for (int k = 0; k < uThetaSamples; k++) {
    float th = float(k) * dth;
    float c = cos(th), s = sin(th);
    vec3 q = uCircleCenter + r * (c * uCircleN + s * uCircleB) - p;
    vec3 perp = q - dot(q, n) * n;
    float g = dot(perp, perp);
    if (g < best) { best = g; bc = c; bs = s; }
  }
  for (int it = 0; it < 3; it++) {
    vec3 rad = r * (bc * uCircleN + bs * uCircleB);
    vec3 l1 = r * (-bs * uCircleN + bc * uCircleB);
    vec3 q = uCircleCenter + rad - p;
    float qn = dot(q, n), l1n = dot(l1, n);
    float h1 = dot(q, l1) - qn * l1n;
    float h2 = dot(l1, l1) - dot(q, rad) - l1n * l1n + qn * dot(rad, n);
    if (!(h2 > 0.0)) break;
    float st = -h1 / h2;
    float k = inversesqrt(1.0 + st * st);
    float c2 = (bc - st * bs) * k, s2 = (bs + st * bc) * k;
    bc = c2; bs = s2;
  }
  vec3 lp = uCircleCenter + r * (bc * uCircleN + bs * uCircleB);
  vec3 w = lp - p;
  vec3 d = w - dot(w, n) * n;
  vec3 ldot = r * (-bs * uCircleN + bc * uCircleB);
  vec3 m = cross(n, ldot);
  float ml = length(m);
  valid = ml > 1e-6 * r;
  return valid ? dot(d, m) / ml : 0.0;
}

void main() {
  vec3 n = normalize(vNormal);
  if (!gl_FrontFacing) n = -n;
  vec3 view = normalize(uEye - vPos);
  float diffuse = abs(dot(n, view));
  vec3 base = uBaseColor;
  if (uScalarOn == 1) {
    float t = clamp((vScalar - uScalarLo) / max(uScalarHi - uScalarLo, 1e-30), 0.0, 1.0);
    base = texture(uColormap, vec2(t, 0.5)).rgb;
  }
  vec3 color = base * (0.25 + 0.75 * diffuse);
  vec3 nn = normalize(vNormal);
  if (uMode == 1 || uMode == 2) {
    float zn = dot(uZ, nn);
    if (abs(zn) >= uMinCos) {
      float d = dot(cross(vPos - uA0, nn), uH) / zn;
      float t = d / uSpacing;
      float off = abs(t - floor(t + 0.5)) * uSpacing; // |d − m·s| for the nearest m
      if (uMode == 1) {
        float w = fwidth(d) * uLineWidth;
        float a = 1.0 - smoothstep(0.5 * w, w, off);
        // lines closer than about three pixels cannot be told apart: fade
        // them out instead of painting the area black
        a *= 1.0 - smoothstep(0.15, 0.35, fwidth(d) / uSpacing);
        color = mix(color, vec3(0.02), a);
      } else {
        float aa = fwidth(d);
        float a = 1.0 - smoothstep(uBandHalf - aa, uBandHalf + aa, off);
        a = mix(a, uBandHalf / uSpacing, smoothstep(0.15, 0.35, aa / uSpacing));
        color = mix(color, vec3(0.02), a);
      }
    }
  } else if (uMode == 3) {
    float ang = acos(clamp(dot(uZ, nn), -1.0, 1.0)) * (180.0 / PI);
    float step = max(uSpacing, 1e-6);
    float t = ang / step;
    float off = abs(t - floor(t + 0.5));
    float w = fwidth(t) * uLineWidth;
    float a = 1.0 - smoothstep(0.5 * w, w, off);
    color = mix(color, vec3(0.02), a);
  } else if (uMode == 6) {
    vec3 r = reflect(-view, n);
    vec3 b = cross(uH, uZ);
    float ang = atan(dot(r, b), dot(r, uZ)) * (180.0 / PI);
    float t = ang / max(uSpacing, 1e-6);
    // the angle jumps by 360° behind the axis: the width of the step, not
    // of the jump, is the filter's
    float aa = min(fwidth(t), 0.5);
    float off = abs(t - floor(t + 0.5));
    float a = 1.0 - smoothstep(uBandHalf - aa, uBandHalf + aa, off);
    a = mix(a, 2.0 * uBandHalf, smoothstep(0.15, 0.35, aa));
    color = mix(color, vec3(0.02), a);
  } else if (uMode == 4 || uMode == 5) {
    float a = 0.0;
    for (int i = 0; i < min(uRadiusCount, 16); i++) {
      bool ok;
      float ds = circleDistance(vPos, nn, uRadii[i], ok);
      if (!ok) continue;
      if (uMode == 4) {
        float w = fwidth(ds) * uLineWidth;
        a = max(a, 1.0 - smoothstep(0.5 * w, w, abs(ds)) * 1.0);
      } else {
        float aa = fwidth(ds);
        a = max(a, 1.0 - smoothstep(uBandHalf - aa, uBandHalf + aa, abs(ds)));
      }
    }
    color = mix(color, vec3(0.02), a);
  }
  outColor = vec4(color, 1.0);
}
