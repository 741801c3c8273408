// The camera and the canvas: the camera framing the scene (or the scene's own), its orbit
// controls kept above the floor in 3D, and the canvas following the window.
//
// 3D: a perspective camera looking from VIEW_DIRECTION, z up, placed so that the extent and
// the colliders' corners fill the view at the canvas's aspect ratio, its orbit kept above the
// floor (see keepAboveFloor); 2D: an orthographic camera on the xy-plane, fitted likewise. A
// scene's own camera (meta.camera) replaces the fitted view: 3D the pinhole at eye looking at
// target with its up and vertical field of view, as kinema's renderer draws it; 2D its
// rectangle fitted to the canvas, centred, aspect kept. Refitted on resize until the user
// moves the camera.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { boxCorners, vec } from "./scenery.js";

const FIT_MARGIN = 0.94; // the scene fills this much of the view's half-width or half-height
const VIEW_DIRECTION = [0.9, -1.1, 0.6]; // from the scene towards the 3D camera (z up)
const FLOOR_CLEARANCE = 0.002; // of the extent's diagonal: how far above the floor the 3D camera stays

// Keeps the 3D orbit above the floor (height `floor`): the camera at least `clearance` over
// it and the orbit's target not under it. OrbitControls clamps the polar angle (from +z, the
// camera's up) to maxPolarAngle before it pans and zooms, so the limit is set from the target
// and distance before each update, and an update whose pan or zoom still took the camera
// below is followed by one more (no frame is drawn in between): a pan stops at the floor
// (target and camera lifted together), an orbit or a zoom at the clearance.
function keepAboveFloor(controls, camera, floor, clearance) {
  const orbit = controls.update.bind(controls);
  const limit = () => {
    const d = Math.max(camera.position.distanceTo(controls.target), 1e-300);
    controls.maxPolarAngle = Math.acos(Math.min(1, Math.max(-1, (floor + clearance - controls.target.z) / d)));
  };
  controls.minDistance = 2 * clearance; // the camera can be over the floor above a target on it
  // OrbitControls' own handlers call this.update(), which is this from now on.
  controls.update = (deltaTime = null) => {
    limit();
    let changed = orbit(deltaTime);
    const lift = floor - controls.target.z;
    if (lift > 0) {
      controls.target.z += lift;
      camera.position.z += lift;
    }
    if (lift > 0 || camera.position.z < floor + clearance * (1 - 1e-6)) {
      limit();
      changed = orbit() || changed;
    }
    return changed;
  };
}

// The 3D camera's place: looking along -VIEW_DIRECTION with z up, as near as it can be with
// every point inside the field of view (`margin` of it): for camera axes r (right), u (up),
// f (forward), a point p is in view when |p·r − a| <= tH (p·f − c) and |p·u − b| <= tV (p·f − c),
// the camera at a r + b u + c f. Each pair of bounds on c is largest (the camera nearest)
// where the two meet: c = (A + B) / 2 at a = (B − A) tH / 2, A = min(p·f − p·r / tH),
// B = min(p·f + p·r / tH), and likewise for b; the camera takes the smaller c (the other
// direction is then centred with room to spare).
function fitPerspective(points, fovDeg, aspect) {
  const f = vec(VIEW_DIRECTION).normalize().negate();
  const r = new THREE.Vector3().crossVectors(f, new THREE.Vector3(0, 0, 1)).normalize();
  const u = new THREE.Vector3().crossVectors(r, f);
  const tV = Math.tan(THREE.MathUtils.degToRad(fovDeg) / 2) * FIT_MARGIN;
  const tH = tV * aspect;
  let [ah, bh, av, bv] = [Infinity, Infinity, Infinity, Infinity];
  let farthest = -Infinity;
  const centre = new THREE.Vector3();
  for (const p of points) {
    const [pr, pu, pf] = [p.dot(r), p.dot(u), p.dot(f)];
    ah = Math.min(ah, pf - pr / tH);
    bh = Math.min(bh, pf + pr / tH);
    av = Math.min(av, pf - pu / tV);
    bv = Math.min(bv, pf + pu / tV);
    farthest = Math.max(farthest, pf);
    centre.add(p);
  }
  centre.multiplyScalar(1 / points.length);
  const a = ((bh - ah) * tH) / 2;
  const b = ((bv - av) * tV) / 2;
  const c = Math.min((ah + bh) / 2, (av + bv) / 2);
  const eye = r.clone().multiplyScalar(a).addScaledVector(u, b).addScaledVector(f, c);
  // The orbit's target: on the axis of view, at the depth of the points' centre.
  const depth = Math.max(centre.clone().sub(eye).dot(f), 1e-9);
  return { eye, target: eye.clone().addScaledVector(f, depth), far: farthest - c };
}

// The extent of the scene (`elo`, `ehi`, its `centre` and its diagonal `extent`) and what the
// camera frames (`framed`).
export function framing(meta, drawn) {
  const elo = vec(meta.extent.min);
  const ehi = vec(meta.extent.max);
  const centre = elo.clone().add(ehi).multiplyScalar(0.5);
  const extent = Math.max(ehi.clone().sub(elo).length(), 1e-9);
  // What the camera frames: the extent's corners (the particles over every frame and the
  // colliders' finite parts) and the corners of what the colliders drew (floor patches).
  const framed = boxCorners(elo, ehi).concat(drawn.corners);
  return { elo, ehi, centre, extent, framed };
}

// The camera (not yet placed: see fit) and its orbit controls on the renderer's canvas, for
// the scene framed by `box` (see framing). The camera's record holds them with the scene's
// own camera (`given`, null without one), the floor the 3D orbit stays above (`floor`, null
// without one) and its `clearance`, and `userMoved`.
export function buildCamera(meta, renderer, drawn, box) {
  const dim = meta.dim;
  const { extent } = box;
  const camera = dim === 2 ? new THREE.OrthographicCamera(-1, 1, 1, -1, extent * 1e-3, extent * 100) : new THREE.PerspectiveCamera(45, 1, extent * 1e-3, extent * 100);
  if (dim !== 2) camera.up.set(0, 0, 1); // kinema's worlds have z up (gravity along -z)
  // The scene's own camera ([render] camera), when it has one: the view the page opens with.
  // Its up and field of view are set before the orbit controls are made (they orbit about up).
  const given = meta.camera ?? null;
  if (given && given.type === "3d" && dim !== 2) {
    camera.up.fromArray(given.up).normalize();
    camera.fov = given.fovDeg;
  }
  const controls = new OrbitControls(camera, renderer.domElement);
  if (dim === 2) {
    controls.enableRotate = false; // a plane seen from above; pan and zoom
    controls.screenSpacePanning = true;
  }
  const floor = dim === 2 ? null : drawn.floor;
  const clearance = FLOOR_CLEARANCE * extent;
  const cam = { ...box, dim, camera, controls, given, floor, clearance };
  cam.userMoved = false; // the camera is refitted on resize until the user moves it
  controls.addEventListener("start", () => (cam.userMoved = true));
  if (floor !== null) keepAboveFloor(controls, camera, floor, clearance);
  return cam;
}

// Place the camera so that everything framed is in view at the canvas's aspect ratio, or
// where the scene's camera says.
export function fit(cam, aspect) {
  const { dim, camera, controls, given, floor, elo, ehi, centre, extent, framed } = cam;
  if (given && given.type === "2d" && dim === 2) {
    // The rectangle fits the canvas, centred, aspect kept (as kinema's renderer draws it).
    const [x0, y0, x1, y1] = given.view;
    const half = Math.max((y1 - y0) / 2, (x1 - x0) / 2 / aspect, 1e-300);
    Object.assign(camera, { left: -half * aspect, right: half * aspect, top: half, bottom: -half, zoom: 1 });
    const cx = (x0 + x1) / 2;
    const cy = (y0 + y1) / 2;
    camera.position.set(cx, cy, ehi.z + extent);
    camera.near = extent * 1e-3;
    camera.far = ehi.z - elo.z + 3 * extent;
    controls.target.set(cx, cy, centre.z);
  } else if (given && given.type === "3d" && dim !== 2) {
    camera.aspect = aspect;
    const eye = vec(given.eye);
    const target = vec(given.target);
    let far = 0;
    for (const p of framed) far = Math.max(far, p.distanceTo(eye));
    camera.position.copy(eye);
    camera.near = Math.max(eye.distanceTo(target), extent) * 1e-3;
    camera.far = 10 * Math.max(far, extent);
    controls.target.copy(target);
  } else if (dim === 2) {
    let [x0, x1, y0, y1] = [Infinity, -Infinity, Infinity, -Infinity];
    for (const p of framed) {
      [x0, x1, y0, y1] = [Math.min(x0, p.x), Math.max(x1, p.x), Math.min(y0, p.y), Math.max(y1, p.y)];
    }
    const half = Math.max((y1 - y0) / 2, (x1 - x0) / 2 / aspect, 1e-9) / FIT_MARGIN;
    Object.assign(camera, { left: -half * aspect, right: half * aspect, top: half, bottom: -half, zoom: 1 });
    const cx = (x0 + x1) / 2;
    const cy = (y0 + y1) / 2;
    camera.position.set(cx, cy, ehi.z + extent);
    camera.near = extent * 1e-3;
    camera.far = ehi.z - elo.z + 3 * extent;
    controls.target.set(cx, cy, centre.z);
  } else {
    camera.aspect = aspect;
    const { eye, target, far } = fitPerspective(framed, camera.fov, aspect);
    camera.position.copy(eye);
    camera.near = Math.max(eye.distanceTo(target), extent) * 1e-3;
    camera.far = 10 * Math.max(far, extent);
    controls.target.copy(target);
    // An orbit target under the floor slides along the line of sight up to it (the view is
    // the same; the floor keeps targets out from under it).
    const ahead = target.clone().sub(eye);
    if (floor !== null && target.z < floor && ahead.z < 0) controls.target.copy(eye).addScaledVector(ahead, (eye.z - floor) / -ahead.z);
  }
  camera.updateProjectionMatrix();
  controls.update();
}

// The canvas's size in CSS pixels: its container's (the window's while that has none).
export function canvasSize(container) {
  return [container.clientWidth || window.innerWidth, container.clientHeight || window.innerHeight];
}

// Pixels per metre for the particles' sprites (at 1 m depth in perspective).
export function pointScale(v) {
  const { camera } = v.cam;
  const pixels = canvasSize(v.container)[1] * v.renderer.getPixelRatio();
  v.particles.material.uniforms.uPixelsPerUnit.value =
    v.dim === 2 ? (pixels * camera.zoom) / (camera.top - camera.bottom) : pixels / (2 * Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2));
}

// The canvas at the container's size: the camera refitted to it (until the user moved it;
// then its view widened or narrowed), the lines' resolution and the sprites' scale with it.
export function resize(v) {
  const { camera } = v.cam;
  const [w, h] = canvasSize(v.container);
  v.renderer.setSize(w, h, false);
  if (v.cam.userMoved) {
    if (v.dim === 2) {
      // Keep the height in view and widen or narrow the width.
      const half = (camera.top - camera.bottom) / 2;
      Object.assign(camera, { left: (-half * w) / h, right: (half * w) / h });
    } else camera.aspect = w / h;
    camera.updateProjectionMatrix();
  } else fit(v.cam, w / h);
  for (const m of v.drawn.lineMaterials) m.resolution.set(w, h);
  pointScale(v);
  v.dirty = true;
}
