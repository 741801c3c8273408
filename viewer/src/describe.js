// What the page shows, described for the tests (window.kinemaViewer.info()): the colliders,
// particles and springs drawn, the colouring and its legend, the camera and its orbit, and
// how the scene sits on the canvas.

import * as THREE from "three";
import { canvasSize } from "./camera.js";

// A read-only description of what is drawn at the frame shown (for tests): the colliders'
// objects by type, box edges, moving colliders' matrices, springs and particles visible, the legend, whether every
// visible particle (its disc) and every corner of the colliders' drawing project inside
// the canvas (`room`: the least distance in CSS pixels from one to the canvas's border,
// negative outside), and how much of the canvas the framed points span (`fill`, of its
// width and height).
// `v` is the viewer's record (see start in viewer.js).
export function describe(v) {
  const { dim, n, drawn, ui, state, particles, springs, legendShown } = v;
  const { camera, controls, given, floor, clearance, framed } = v.cam;
  const { position, radius, aliveNow, material, noOwn } = particles;
  camera.updateMatrixWorld();
  const [w, h] = canvasSize(v.container);
  const ndc = new THREE.Vector3();
  const view = new THREE.Vector3();
  const perPixel = dim === 2 ? (h * camera.zoom) / (camera.top - camera.bottom) : h / (2 * Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2));
  const box = [Infinity, -Infinity, Infinity, -Infinity];
  // The disc of radius r (m) about p on the canvas: its least distance to the border.
  const room = (p, r, span = false) => {
    view.copy(p).applyMatrix4(camera.matrixWorldInverse);
    if (dim !== 2 && view.z >= 0) return -Infinity; // behind the camera
    ndc.copy(p).project(camera);
    const px = ((ndc.x + 1) / 2) * w;
    const py = ((1 - ndc.y) / 2) * h;
    if (span) [box[0], box[1], box[2], box[3]] = [Math.min(box[0], px), Math.max(box[1], px), Math.min(box[2], py), Math.max(box[3], py)];
    const rp = dim === 2 ? r * perPixel : (r * perPixel) / -view.z;
    return Math.min(px - rp, w - px - rp, py - rp, h - py - rp);
  };
  let particleRoom = Infinity;
  const p = new THREE.Vector3();
  const frame = position.array;
  for (let i = 0; i < n; i++) {
    if (!aliveNow[i]) continue;
    p.fromArray(frame, 3 * i);
    particleRoom = Math.min(particleRoom, room(p, radius.array[i]));
  }
  // A moving collider's corners where it is now.
  const placed = drawn.corners.map((c) => c.clone());
  for (const m of drawn.moving) for (let i = m.first; i < m.end; i++) placed[i].applyMatrix4(m.group.matrix);
  let colliderRoom = Infinity;
  for (const c of placed) colliderRoom = Math.min(colliderRoom, room(c, 0));
  let framedRoom = Infinity;
  for (const c of framed) framedRoom = Math.min(framedRoom, room(c, 0, true));
  return {
    frame: state.frame,
    dim,
    canvas: { width: w, height: h },
    colliders: { ...drawn.counts },
    boxEdges: drawn.boxEdges,
    meshes: drawn.meshes,
    colliderCorners: drawn.corners.length,
    // Each moving collider's type and the matrix (column-major) its objects are drawn with.
    moving: drawn.moving.map((m) => ({ type: m.type, matrix: Array.from(m.group.matrix.elements) })),
    particles: { total: n, visible: particles.visible },
    springs: { total: springs.count, visible: springs.visible },
    legend: legendShown ? { shown: true, label: legendShown.label, min: legendShown.min, max: legendShown.max, text: ui.legend.innerText } : { shown: false },
    colouring: { choice: v.colouring, mode: material.uniforms.uMode.value, options: Array.from(ui.colour.options, (o) => o.value), noOwnColor: noOwn.map((c) => Math.round(255 * c)) },
    // The orbit: polar angle from +z (rad) and its limit, the floor's height (null: none).
    camera: {
      given: given ? given.type : null, // the scene's camera opened the view (null: fitted)
      position: camera.position.toArray(),
      target: controls.target.toArray(),
      up: camera.up.toArray(),
      fov: dim === 2 ? null : camera.fov,
      // 2D: the xy rectangle seen (xmin, ymin, xmax, ymax); 3D: null
      view:
        dim === 2
          ? [
              camera.position.x + camera.left / camera.zoom,
              camera.position.y + camera.bottom / camera.zoom,
              camera.position.x + camera.right / camera.zoom,
              camera.position.y + camera.top / camera.zoom,
            ]
          : null,
      polar: controls.getPolarAngle(),
      maxPolar: controls.maxPolarAngle,
      floor,
      clearance: floor === null ? null : clearance,
    },
    // Half a pixel of slack for rounding (Infinity: nothing to check).
    inView: { particles: particleRoom >= -0.5, colliders: colliderRoom >= -0.5, particleRoom, colliderRoom, framedRoom },
    fill: [(box[1] - box[0]) / w, (box[3] - box[2]) / h],
  };
}
