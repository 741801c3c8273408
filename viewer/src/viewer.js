//! kinema trajectory viewer: frames as THREE.Points with a sprite shader, the colliders and
//! springs, an orbit camera framing the scene, a colour legend and a small UI.
//
// The page's data and the URL hash's options: data.js.
//
// Drawn: the particles alive at the frame (the others are moved out of the clip volume by
// the vertex shader); springs as lines between live ends; planes as a floor patch (3D) or a
// line with its solid side filled (2D); boxes as their edges less those of open faces, with
// the walls of open faces reaching the extent, and a floor face; sphere obstacles as shaded
// spheres (3D) or discs (2D); triangle meshes (3D) as a translucent lit surface seen from
// both sides, with its rim and creases as lines, so that what is inside shows. A moving
// collider's objects sit in a group of their own whose matrix is set to its pose at the
// frame shown (planes, boxes, spheres and meshes alike). The camera: camera.js.
//
// Colourings: colours.js.
//
// `window.kinemaViewer` is the page's state for tests and benchmarks: `ready`, `error`,
// `frame` (the trajectory frame shown), `playing`, `setFrame(k)`, `stats`, the frame
// statistics (see frameStats in stats.js): `stats.snapshot()` gives animation frames run, frames drawn,
// trajectory frames stepped and median frame times in ms over the last STATS_WINDOW frames;
// `info()`, a read-only description of what is drawn (see `describe` in start: the colouring,
// the legend, the orbit camera and its floor, ...); and `ownColours()`, the RGB bytes "color"
// gives each particle, read from the colour buffer drawn (see `ownColourBytes` in particles.js).

import * as THREE from "three";
import { hashOptions, loadData } from "./data.js";
import { frameStats } from "./stats.js";
import { legendValue } from "./colours.js";
import { buildScenery } from "./scenery.js";
import { buildCamera, fit as fitCamera, framing } from "./camera.js";
import { buildParticles } from "./particles.js";
import { buildSprings } from "./springs.js";
import { buildUi } from "./ui.js";

const BACKGROUND = 0x101014;

function start({ meta, positions, speed, radii, springs, alive, colors }) {
  const n = meta.n;
  const frames = meta.frames;
  const times = meta.t;
  const dim = meta.dim;
  const container = document.getElementById("kinema-view");

  // No MSAA: the discs are cut out by `discard`, which multisampling does not smooth, so it
  // would only multiply the fill work; and no preserved drawing buffer, which costs a copy of
  // the canvas every frame (the compositor still shows the last frame drawn).
  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: false });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(BACKGROUND, 1);
  container.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  const scenery = new THREE.Group();
  scene.add(scenery);
  const drawn = buildScenery(meta, scenery);
  const box = framing(meta, drawn);
  const { centre, extent, framed } = box;
  const cam = buildCamera(meta, renderer, drawn, box);
  const { camera, controls, given, floor, clearance } = cam;
  const fit = (aspect) => fitCamera(cam, aspect);

  const particles = buildParticles(meta, { positions, speed, radii, alive, colors }, centre, extent);
  const { position, radius, aliveNow, material, noOwn, offerOwn } = particles;
  scene.add(particles.points);

  const springLines = buildSprings(springs, dim);
  if (springLines.count) scene.add(springLines.lines);

  const ui = buildUi(document.body, container);
  ui.scrub.max = String(frames - 1);
  if (!speed) ui.colour.querySelector('option[value="speed"]').disabled = true;
  if (!offerOwn) ui.colour.querySelector('option[value="color"]').remove();
  // The colouring the trajectory asks for (a scene's [render] color_by) where the page has it,
  // else speed (id when the speeds are unknown).
  const offered = (v) => Array.from(ui.colour.options).some((o) => o.value === v && !o.disabled);
  ui.colour.value = offered(meta.colorBy) ? meta.colorBy : speed ? "speed" : "id";

  const state = window.kinemaViewer;
  let colouring = ui.colour.value;
  let playbackSpeed = Number(ui.speed.value);
  let playbackTime = times[0];
  // Playback loops from the first frame to one frame interval past the last, so that the last
  // frame is shown as long as the others before the first comes round again.
  const loopEnd = frames > 1 ? 2 * times[frames - 1] - times[frames - 2] : times[0];
  let dirty = true;
  const infoSuffix = meta.note ? ` · ${meta.note}` : "";
  let legendShown = null;

  // The legend names what the colours show and the values at the ends of the ramp.
  function setLegend() {
    legendShown = null;
    if (colouring === "speed" && speed) legendShown = { label: "speed (m/s)", min: meta.speedMin, max: meta.speedMax };
    else if (colouring === "id") legendShown = { label: "particle id", min: meta.idRange[0], max: meta.idRange[1], integer: true };
    ui.legend.style.display = legendShown ? "" : "none";
    if (legendShown) {
      ui.legendLabel.textContent = legendShown.label;
      ui.legendMin.textContent = legendValue(legendShown.min, legendShown.integer);
      ui.legendMax.textContent = legendValue(legendShown.max, legendShown.integer);
    }
  }

  // Moving colliders where they are at frame k: each one's group takes its pose.
  function placeColliders(k) {
    for (const m of drawn.moving) {
      m.group.matrix.fromArray(m.poses, 16 * k);
      m.group.matrixWorldNeedsUpdate = true;
    }
  }

  function setFrame(k, keepTime = false) {
    k = Math.max(0, Math.min(frames - 1, Math.round(k)));
    if (k !== state.frame) {
      placeColliders(k);
      particles.place(k);
      particles.fillAlive(k);
      springLines.fill(position.array, aliveNow);
      if (colouring === "speed") particles.fillColour(colouring, k); // id and none do not change with the frame
      state.stats.steps++;
      ui.scrub.value = String(k);
      const count = alive ? `${particles.visible.toLocaleString()} of ${n.toLocaleString()}` : n.toLocaleString();
      ui.info.textContent = `${count} ${n === 1 ? "particle" : "particles"} · t = ${times[k].toFixed(3)} s · frame ${k + 1}/${frames}${infoSuffix}`;
    }
    state.frame = k;
    if (!keepTime) playbackTime = times[k];
    dirty = true;
  }

  function setPlaying(on) {
    state.playing = on && frames > 1;
    ui.play.textContent = state.playing ? "❚❚" : "▶";
  }

  function canvasSize() {
    return [container.clientWidth || window.innerWidth, container.clientHeight || window.innerHeight];
  }

  // Pixels per metre for the particles' sprites (at 1 m depth in perspective).
  function pointScale() {
    const pixels = canvasSize()[1] * renderer.getPixelRatio();
    material.uniforms.uPixelsPerUnit.value =
      dim === 2 ? (pixels * camera.zoom) / (camera.top - camera.bottom) : pixels / (2 * Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2));
  }

  function resize() {
    const [w, h] = canvasSize();
    renderer.setSize(w, h, false);
    if (cam.userMoved) {
      if (dim === 2) {
        // Keep the height in view and widen or narrow the width.
        const half = (camera.top - camera.bottom) / 2;
        Object.assign(camera, { left: (-half * w) / h, right: (half * w) / h });
      } else camera.aspect = w / h;
      camera.updateProjectionMatrix();
    } else fit(w / h);
    for (const m of drawn.lineMaterials) m.resolution.set(w, h);
    pointScale();
    dirty = true;
  }

  // A read-only description of what is drawn at the frame shown (for tests): the colliders'
  // objects by type, box edges, moving colliders' matrices, springs and particles visible, the legend, whether every
  // visible particle (its disc) and every corner of the colliders' drawing project inside
  // the canvas (`room`: the least distance in CSS pixels from one to the canvas's border,
  // negative outside), and how much of the canvas the framed points span (`fill`, of its
  // width and height).
  function describe() {
    camera.updateMatrixWorld();
    const [w, h] = canvasSize();
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
      springs: { total: springLines.count, visible: springLines.visible },
      legend: legendShown ? { shown: true, label: legendShown.label, min: legendShown.min, max: legendShown.max, text: ui.legend.innerText } : { shown: false },
      colouring: { choice: colouring, mode: material.uniforms.uMode.value, options: Array.from(ui.colour.options, (o) => o.value), noOwnColor: noOwn.map((c) => Math.round(255 * c)) },
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

  ui.play.addEventListener("click", () => {
    if (!state.playing && state.frame >= frames - 1) setFrame(0);
    setPlaying(!state.playing);
  });
  ui.scrub.addEventListener("input", () => {
    setPlaying(false);
    setFrame(Number(ui.scrub.value));
  });
  ui.speed.addEventListener("change", () => (playbackSpeed = Number(ui.speed.value)));
  ui.colour.addEventListener("change", () => {
    colouring = ui.colour.value;
    particles.fillColour(colouring, state.frame);
    setLegend();
    dirty = true;
  });
  window.addEventListener("keydown", (e) => {
    if (e.code === "Space" && e.target.tagName !== "SELECT") {
      e.preventDefault();
      ui.play.click();
    }
  });
  controls.addEventListener("change", () => {
    if (dim === 2) pointScale(); // zooming an orthographic camera changes pixels per metre
    dirty = true;
  });
  window.addEventListener("resize", resize);

  let last = performance.now();
  function tick(now) {
    const begun = performance.now();
    state.stats.tick(now - last);
    const elapsed = Math.min((now - last) / 1000, 0.25); // a hidden tab does not jump far ahead
    last = now;
    if (controls.autoRotate) controls.update(elapsed);
    if (state.playing) {
      // Real time times the chosen speed; the shown frame is the last one at or before it.
      playbackTime += elapsed * playbackSpeed;
      if (playbackTime >= loopEnd) playbackTime = times[0] + (playbackTime - loopEnd);
      let k = state.frame;
      if (times[k] > playbackTime) k = 0;
      while (k + 1 < frames && times[k + 1] <= playbackTime) k++;
      if (k !== state.frame) setFrame(k, true);
    }
    if (dirty) {
      renderer.render(scene, camera);
      dirty = false;
      state.stats.drew(performance.now() - begun);
    }
    requestAnimationFrame(tick);
  }

  const opts = hashOptions();
  state.frame = -1;
  state.setFrame = (k) => {
    setPlaying(false);
    setFrame(k);
    renderer.render(scene, camera);
  };
  state.info = describe;
  state.ownColours = particles.ownColourBytes;
  resize();
  particles.fillColour(colouring, 0);
  setLegend();
  setFrame(opts.frame ?? 0);
  setPlaying(opts.frame === null || opts.play);
  controls.autoRotate = opts.rotate;
  renderer.render(scene, camera);
  state.stats.reset();
  state.ready = true;
  last = performance.now();
  requestAnimationFrame(tick);
}

window.kinemaViewer = { frame: 0, setFrame: () => {}, info: () => null, playing: false, ready: false, error: null, stats: frameStats() };
loadData()
  .then(start)
  .catch((err) => {
    window.kinemaViewer.error = String(err);
    const box = document.createElement("pre");
    box.id = "kinema-error";
    box.textContent = `kinema viewer: ${err}`;
    document.body.appendChild(box);
    throw err;
  });
