// The particles: one THREE.Points whose attributes are views into the trajectory's frames,
// drawn as sprites shaded as spheres (shaders.js), the ones not alive at the frame moved out
// of the clip volume; their colouring and, for the tests, the colours "color" gives them.

import * as THREE from "three";
import { FRAGMENT, VERTEX } from "./shaders.js";

// The particles of the trajectory (`n` of them, `meta.frames` frames) as `points`, at frame 0,
// with what the frames step: place(k) (the positions), fillAlive(k) (which are alive: `aliveNow`,
// `visible` of them), fillColour(colouring, k), and ownColourBytes() for the tests. `centre`
// and `extent` (the extent's diagonal) bound where they go.
export function buildParticles(meta, { positions, speed, radii, alive, colors }, centre, extent) {
  const n = meta.n;
  const dim = meta.dim;
  // The attributes hold views into the frame data, not copies: showing frame k points
  // `position` (and `aValue` when colouring by speed) at frame k's slice and marks it for
  // upload, so a step costs the upload alone (no copy, no allocation but the view).
  const frameSlice = (data, k, width) => data.subarray(k * n * width, (k + 1) * n * width);
  const idValues = () => Float32Array.from({ length: n }, (_, i) => (n > 1 ? i / (n - 1) : 0.5));
  let ids = speed ? null : idValues(); // the id ramp, made when first asked for
  const geometry = new THREE.BufferGeometry();
  const position = new THREE.BufferAttribute(frameSlice(positions, 0, 3), 3).setUsage(THREE.DynamicDrawUsage);
  const value = new THREE.BufferAttribute(speed ? frameSlice(speed, 0, 1) : ids, 1).setUsage(THREE.DynamicDrawUsage);
  const radius = new THREE.BufferAttribute(radii ? radii : new Float32Array(n).fill(meta.defaultRadius), 1);
  // Which particles are alive at the frame shown (all, without births and deaths).
  const aliveNow = new Uint8Array(n).fill(1);
  const aliveAttr = new THREE.BufferAttribute(aliveNow, 1).setUsage(alive ? THREE.DynamicDrawUsage : THREE.StaticDrawUsage);
  geometry.setAttribute("position", position);
  geometry.setAttribute("aValue", value);
  geometry.setAttribute("aRadius", radius);
  geometry.setAttribute("aAlive", aliveAttr);
  // Each particle's own colour, RGBA bytes (A 0: none), for "color": offered when some
  // particle has one, or when the trajectory asks for it (then all may have none).
  const offerOwn = colors !== null || meta.colorBy === "color";
  const ownColours = colors ?? (offerOwn ? new Uint8Array(4 * n) : null);
  if (ownColours) geometry.setAttribute("aColor", new THREE.BufferAttribute(ownColours, 4, true));
  const noOwn = (meta.noOwnColor ?? [70, 130, 200]).map((c) => c / 255);
  geometry.boundingSphere = new THREE.Sphere(centre, extent * 10); // frames move: never cull
  const material = new THREE.ShaderMaterial({
    uniforms: { uPixelsPerUnit: { value: 1 }, uOrtho: { value: dim === 2 ? 1 : 0 }, uOffset: { value: 0 }, uScale: { value: 1 }, uMode: { value: 1 }, uNoOwn: { value: new THREE.Vector3(...noOwn) } },
    vertexShader: VERTEX,
    fragmentShader: FRAGMENT,
  });
  const points = new THREE.Points(geometry, material);
  points.frustumCulled = false;

  const particles = {
    points,
    geometry,
    material,
    position,
    radius,
    aliveNow,
    noOwn,
    ownColours,
    offerOwn,
    visible: n, // how many are alive at the frame shown
    // The positions at frame k: a view of the frame's slice, uploaded.
    place(k) {
      position.array = frameSlice(positions, k, 3);
      position.needsUpdate = true;
    },
    // Point aValue at what the colouring needs at frame k and set the ramp; only colouring by
    // speed changes from frame to frame, and "none" uploads nothing.
    fillColour(colouring, k) {
      if (colouring === "speed" && speed) {
        value.array = frameSlice(speed, k, 1);
        value.needsUpdate = true;
        const range = meta.speedMax - meta.speedMin;
        material.uniforms.uOffset.value = meta.speedMin;
        material.uniforms.uScale.value = range > 0 ? 1 / range : 0;
        material.uniforms.uMode.value = 1;
      } else if (colouring === "id") {
        if (value.array !== ids) {
          value.array = ids ??= idValues();
          value.needsUpdate = true;
        }
        material.uniforms.uOffset.value = 0;
        material.uniforms.uScale.value = 1;
        material.uniforms.uMode.value = 1;
      } else {
        material.uniforms.uMode.value = colouring === "color" && ownColours ? 2 : 0;
      }
    },
    // Which particles are alive at frame k.
    fillAlive(k) {
      if (alive) {
        const stride = meta.aliveBytes;
        const row = alive.subarray(k * stride, (k + 1) * stride);
        let visible = 0;
        for (let i = 0; i < n; i++) visible += aliveNow[i] = (row[i >> 3] >> (i & 7)) & 1;
        particles.visible = visible;
        aliveAttr.needsUpdate = true;
      }
    },
    // For tests: the colour (RGB bytes) each particle's sprite is given before shading in the
    // "color" colouring, read from the aColor buffer the GPU draws (null when not offered).
    ownColourBytes() {
      const attr = geometry.getAttribute("aColor");
      if (!attr) return null;
      const base = noOwn.map((c) => Math.round(255 * c));
      return Array.from({ length: n }, (_, i) => (attr.array[4 * i + 3] > 127 ? Array.from(attr.array.subarray(4 * i, 4 * i + 3)) : base));
    },
  };
  return particles;
}
