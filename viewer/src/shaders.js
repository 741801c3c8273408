// The GLSL of what the viewer draws with its own shaders: the particles (sprites shaded as
// spheres, coloured by the colouring chosen; the ones not alive moved out of the clip volume),
// the sphere obstacles and the triangle meshes.

import { LOW_END, VIRIDIS } from "./colours.js";

const glslVec = (c) => `vec3(${c.join(", ")})`;

export const VERTEX = /* glsl */ `
uniform float uPixelsPerUnit;  // perspective: viewport height / (2 tan(fov/2)), pixels per metre at 1 m depth;
                               // orthographic: pixels per metre
uniform int uOrtho;            // 1: orthographic (the size does not depend on depth)
uniform float uOffset;         // the value at the bottom of the ramp
uniform float uScale;          // 1 / (the values' range)
uniform int uMode;             // 0: one colour, 1: ramp over aValue, 2: the particle's own colour
uniform vec3 uNoOwn;           // mode 2: the colour of a particle without its own
attribute float aRadius;
attribute float aValue;
attribute vec4 aColor;         // the particle's own colour (alpha 0: none)
attribute float aAlive;        // 0: not alive at this frame, not drawn
varying vec3 vColor;

vec3 viridis(float t) {
  const vec3 c0 = ${glslVec(VIRIDIS[0])};
  const vec3 c1 = ${glslVec(VIRIDIS[1])};
  const vec3 c2 = ${glslVec(VIRIDIS[2])};
  const vec3 c3 = ${glslVec(VIRIDIS[3])};
  const vec3 c4 = ${glslVec(VIRIDIS[4])};
  const vec3 c5 = ${glslVec(VIRIDIS[5])};
  const vec3 c6 = ${glslVec(VIRIDIS[6])};
  t = clamp(t, 0.0, 1.0);
  return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
}

void main() {
  if (aAlive < 0.5) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: nothing drawn
    gl_PointSize = 0.0;
    vColor = vec3(0.0);
    return;
  }
  vec4 mv = modelViewMatrix * vec4(position, 1.0);
  gl_Position = projectionMatrix * mv;
  // A sphere of radius r at depth d covers 2 r / d * pixelsPerUnit pixels; never under 2 px.
  float perUnit = uOrtho == 1 ? uPixelsPerUnit : uPixelsPerUnit / max(-mv.z, 1e-6);
  gl_PointSize = max(2.0, 2.0 * aRadius * perUnit);
  const vec3 plain = vec3(0.35, 0.65, 0.95);
  vColor = uMode == 0 ? plain : uMode == 2 ? (aColor.a > 0.5 ? aColor.rgb : uNoOwn) : viridis(${LOW_END.toFixed(2)} + ${(1 - LOW_END).toFixed(2)} * clamp((aValue - uOffset) * uScale, 0.0, 1.0));
}
`;

export const FRAGMENT = /* glsl */ `
varying vec3 vColor;
void main() {
  vec2 p = gl_PointCoord * 2.0 - 1.0;
  float r2 = dot(p, p);
  if (r2 > 1.0) discard;
  // Shade as a sphere lit from the upper left: the disc's normal is (p, sqrt(1 - r2)).
  vec3 n = vec3(p.x, -p.y, sqrt(1.0 - r2));
  float diffuse = max(dot(n, normalize(vec3(-0.4, 0.5, 0.8))), 0.0);
  gl_FragColor = vec4(vColor * (0.3 + 0.7 * diffuse), 1.0);
}
`;

// Sphere obstacles, shaded as the particles are (the same light, in view space).
export const OBSTACLE_VERTEX = /* glsl */ `
varying vec3 vNormal;
void main() {
  vNormal = normalize(normalMatrix * normal);
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}
`;
export const OBSTACLE_FRAGMENT = /* glsl */ `
uniform vec3 uColor;
varying vec3 vNormal;
void main() {
  float diffuse = max(dot(normalize(vNormal), normalize(vec3(-0.4, 0.5, 0.8))), 0.0);
  gl_FragColor = vec4(uColor * (0.3 + 0.7 * diffuse), 1.0);
}
`;

// Triangle meshes: each triangle flat (its normal from the derivatives of the view-space
// position across it) and turned towards the eye, so both sides are lit; translucent.
export const MESH_VERTEX = /* glsl */ `
varying vec3 vView;
void main() {
  vec4 mv = modelViewMatrix * vec4(position, 1.0);
  vView = mv.xyz;
  gl_Position = projectionMatrix * mv;
}
`;
export const MESH_FRAGMENT = /* glsl */ `
uniform vec3 uColor;
uniform float uOpacity;
uniform float uAmbient;
varying vec3 vView;
void main() {
  vec3 n = normalize(cross(dFdx(vView), dFdy(vView)));
  if (dot(n, vView) > 0.0) n = -n;
  float diffuse = max(dot(n, normalize(vec3(-0.4, 0.5, 0.8))), 0.0);
  gl_FragColor = vec4(uColor * (uAmbient + (1.0 - uAmbient) * diffuse), uOpacity);
}
`;
