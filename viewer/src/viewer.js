//! kinema trajectory viewer: frames as THREE.Points with a sprite shader, an orbit camera and a small UI.
//
// The page carries `<script type="application/json" id="kinema-data">` with the metadata
// written by python/kinema/viewer: n (particles), frames, dim, t (times, s), bounds
// {min, max} (m), speedMax (m/s), note, and either base64 blobs (positions, speed, radii:
// little-endian float32) or `source` naming a binary file served beside the page whose
// layout is given by `layout` (byte offsets of positions, speed, radii).
// A URL hash `#frame=K` opens paused at frame K (used by the tests); `#frame=K&play=1` plays;
// `rotate=1` turns the orbit camera about its target (a turntable; the benchmark draws every
// animation frame that way).
//
// `window.kinemaViewer` is the page's state for tests and benchmarks: `ready`, `error`,
// `frame` (the trajectory frame shown), `playing`, `setFrame(k)`, and `stats`, the frame
// statistics (see frameStats): `stats.snapshot()` gives animation frames run, frames drawn,
// trajectory frames stepped and median frame times in ms over the last STATS_WINDOW frames.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

const SPEEDS = [0.25, 0.5, 1, 2, 4];
const STATS_WINDOW = 120; // animation frames the medians are taken over (2 s at 60 Hz)

// Viridis by a degree-6 polynomial fit per channel (good to about 1/255 of the table).
const VERTEX = /* glsl */ `
uniform float uPixelsPerUnit;  // viewport height / (2 tan(fov/2)): pixels per metre at 1 m depth
uniform float uScale;          // 1 / the value that maps to the top of the ramp
uniform int uMode;             // 0: one colour, 1: ramp over aValue
attribute float aRadius;
attribute float aValue;
varying vec3 vColor;

vec3 viridis(float t) {
  const vec3 c0 = vec3(0.2777273272234177, 0.005407344544966578, 0.3340998053353061);
  const vec3 c1 = vec3(0.1050930431085774, 1.404613529898575, 1.384590162594685);
  const vec3 c2 = vec3(-0.3308618287255563, 0.214847559468213, 0.09509516302823659);
  const vec3 c3 = vec3(-4.634230498983486, -5.799100973351585, -19.33244095627987);
  const vec3 c4 = vec3(6.228269936347081, 14.17993336680509, 56.69055260068105);
  const vec3 c5 = vec3(4.776384997670288, -13.74514537774601, -65.35303263337234);
  const vec3 c6 = vec3(-5.435455855934631, 4.645852612178535, 26.3124352495832);
  t = clamp(t, 0.0, 1.0);
  return c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * (c5 + t * c6)))));
}

void main() {
  vec4 mv = modelViewMatrix * vec4(position, 1.0);
  gl_Position = projectionMatrix * mv;
  // A sphere of radius r at depth d covers 2 r / d * pixelsPerUnit pixels; never under 2 px.
  gl_PointSize = max(2.0, 2.0 * aRadius * uPixelsPerUnit / max(-mv.z, 1e-6));
  vColor = uMode == 0 ? vec3(0.35, 0.65, 0.95) : viridis(aValue * uScale);
}
`;

const FRAGMENT = /* glsl */ `
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

function decodeBase64(text) {
  const bin = atob(text);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Float32Array(bytes.buffer);
}

async function loadData() {
  const meta = JSON.parse(document.getElementById("kinema-data").textContent);
  if (meta.source) {
    const response = await fetch(meta.source);
    if (!response.ok) throw new Error(`${meta.source}: HTTP ${response.status}`);
    const buffer = await response.arrayBuffer();
    const view = (entry) => (entry ? new Float32Array(buffer, entry[0], entry[1]) : null);
    return { meta, positions: view(meta.layout.positions), speed: view(meta.layout.speed), radii: view(meta.layout.radii) };
  }
  const blob = (text) => (text ? decodeBase64(text) : null);
  return { meta, positions: blob(meta.positions), speed: blob(meta.speed), radii: blob(meta.radii) };
}

function hashOptions() {
  const params = new URLSearchParams(location.hash.slice(1));
  const frame = params.has("frame") ? parseInt(params.get("frame"), 10) : null;
  return { frame: Number.isFinite(frame) ? frame : null, play: params.get("play") === "1", rotate: params.get("rotate") === "1" };
}

// Counters and the last STATS_WINDOW frame times in rings (no allocation per frame); the
// medians are computed when read. Times in ms: `frameMs`, between consecutive animation
// frames (1000 / frameMs is the frame rate the page reaches, at most the display's);
// `drawMs`, the script's work in the frames that drew (setting the frame and rendering:
// the GPU's work is not in it). A median is null before any frame was measured.
function frameStats() {
  const intervals = new Float64Array(STATS_WINDOW);
  const work = new Float64Array(STATS_WINDOW);
  const scratch = new Float64Array(STATS_WINDOW);
  const median = (ring, count) => {
    const m = Math.min(count, STATS_WINDOW);
    if (m === 0) return null;
    const sorted = scratch.subarray(0, m);
    sorted.set(ring.subarray(0, m));
    sorted.sort();
    return m % 2 ? sorted[(m - 1) / 2] : 0.5 * (sorted[m / 2 - 1] + sorted[m / 2]);
  };
  const stats = {
    ticks: 0, // animation frames run
    draws: 0, // animation frames that drew the scene
    steps: 0, // trajectory frames shown (each change of the shown frame)
    tick(intervalMs) {
      intervals[stats.ticks++ % STATS_WINDOW] = intervalMs;
    },
    drew(workMs) {
      work[stats.draws++ % STATS_WINDOW] = workMs;
    },
    reset() {
      stats.ticks = stats.draws = stats.steps = 0;
    },
    snapshot() {
      const frameMs = median(intervals, stats.ticks);
      return { ticks: stats.ticks, draws: stats.draws, steps: stats.steps, frameMs, fps: frameMs ? 1000 / frameMs : null, drawMs: median(work, stats.draws), window: STATS_WINDOW };
    },
  };
  return stats;
}

function buildUi(root) {
  const bar = document.createElement("div");
  bar.id = "kinema-ui";
  bar.innerHTML = `
    <button id="kinema-play" title="play / pause (space)">▶</button>
    <input id="kinema-scrub" type="range" min="0" max="0" value="0" step="1">
    <label>speed <select id="kinema-speed">${SPEEDS.map((s) => `<option value="${s}"${s === 1 ? " selected" : ""}>${s}×</option>`).join("")}</select></label>
    <label>colour <select id="kinema-colour"><option value="speed">speed</option><option value="id">id</option><option value="none">none</option></select></label>
    <span id="kinema-info"></span>`;
  root.appendChild(bar);
  const get = (id) => document.getElementById(id);
  return { play: get("kinema-play"), scrub: get("kinema-scrub"), speed: get("kinema-speed"), colour: get("kinema-colour"), info: get("kinema-info") };
}

function start({ meta, positions, speed, radii }) {
  const n = meta.n;
  const frames = meta.frames;
  const times = meta.t;
  const container = document.getElementById("kinema-view");

  // No MSAA: the discs are cut out by `discard`, which multisampling does not smooth, so it
  // would only multiply the fill work; and no preserved drawing buffer, which costs a copy of
  // the canvas every frame (the compositor still shows the last frame drawn).
  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: false });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0x101014, 1);
  container.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  const lo = new THREE.Vector3(...meta.bounds.min);
  const hi = new THREE.Vector3(...meta.bounds.max);
  const center = lo.clone().add(hi).multiplyScalar(0.5);
  const extent = Math.max(hi.clone().sub(lo).length(), 1e-9);
  const camera = new THREE.PerspectiveCamera(45, 1, extent * 1e-3, extent * 100);
  if (meta.dim === 2) {
    camera.position.set(center.x, center.y, center.z + 1.3 * extent);
  } else {
    camera.up.set(0, 0, 1); // kinema's worlds have z up (gravity along -z)
    camera.position.copy(center).add(new THREE.Vector3(0.9, -1.1, 0.6).multiplyScalar(extent * 0.9));
  }
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(center);
  controls.update();

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
  geometry.setAttribute("position", position);
  geometry.setAttribute("aValue", value);
  geometry.setAttribute("aRadius", radius);
  geometry.boundingSphere = new THREE.Sphere(center, extent * 10); // frames move: never cull
  const material = new THREE.ShaderMaterial({
    uniforms: { uPixelsPerUnit: { value: 1 }, uScale: { value: 1 }, uMode: { value: 1 } },
    vertexShader: VERTEX,
    fragmentShader: FRAGMENT,
  });
  const points = new THREE.Points(geometry, material);
  points.frustumCulled = false;
  scene.add(points);

  const ui = buildUi(document.body);
  ui.scrub.max = String(frames - 1);
  if (!speed) ui.colour.querySelector('option[value="speed"]').disabled = true;
  ui.colour.value = speed ? "speed" : "id";

  const state = window.kinemaViewer;
  let colouring = ui.colour.value;
  let playbackSpeed = Number(ui.speed.value);
  let playbackTime = times[0];
  // Playback loops from the first frame to one frame interval past the last, so that the last
  // frame is shown as long as the others before the first comes round again.
  const loopEnd = frames > 1 ? 2 * times[frames - 1] - times[frames - 2] : times[0];
  let dirty = true;
  const infoPrefix = `${n.toLocaleString()} particles · t = `;
  const infoSuffix = meta.note ? ` · ${meta.note}` : "";

  // Point aValue at what the colouring needs at frame k and set the ramp; only colouring by
  // speed changes from frame to frame, and "none" uploads nothing.
  function fillColour(k) {
    if (colouring === "speed" && speed) {
      value.array = frameSlice(speed, k, 1);
      value.needsUpdate = true;
      material.uniforms.uScale.value = meta.speedMax > 0 ? 1 / meta.speedMax : 1;
      material.uniforms.uMode.value = 1;
    } else if (colouring === "id") {
      if (value.array !== ids) {
        value.array = ids ??= idValues();
        value.needsUpdate = true;
      }
      material.uniforms.uScale.value = 1;
      material.uniforms.uMode.value = 1;
    } else {
      material.uniforms.uMode.value = 0;
    }
  }

  function setFrame(k, keepTime = false) {
    k = Math.max(0, Math.min(frames - 1, Math.round(k)));
    if (k !== state.frame) {
      position.array = frameSlice(positions, k, 3);
      position.needsUpdate = true;
      if (colouring === "speed") fillColour(k); // id and none do not change with the frame
      state.stats.steps++;
      ui.scrub.value = String(k);
      ui.info.textContent = `${infoPrefix}${times[k].toFixed(3)} s · frame ${k + 1}/${frames}${infoSuffix}`;
    }
    state.frame = k;
    if (!keepTime) playbackTime = times[k];
    dirty = true;
  }

  function setPlaying(on) {
    state.playing = on && frames > 1;
    ui.play.textContent = state.playing ? "❚❚" : "▶";
  }

  function resize() {
    const w = container.clientWidth || window.innerWidth;
    const h = container.clientHeight || window.innerHeight;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    const pixels = h * renderer.getPixelRatio();
    material.uniforms.uPixelsPerUnit.value = pixels / (2 * Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2));
    dirty = true;
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
    fillColour(state.frame);
    dirty = true;
  });
  window.addEventListener("keydown", (e) => {
    if (e.code === "Space" && e.target.tagName !== "SELECT") {
      e.preventDefault();
      ui.play.click();
    }
  });
  controls.addEventListener("change", () => (dirty = true));
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
  resize();
  fillColour(0);
  setFrame(opts.frame ?? 0);
  setPlaying(opts.frame === null || opts.play);
  controls.autoRotate = opts.rotate;
  renderer.render(scene, camera);
  state.stats.reset();
  state.ready = true;
  last = performance.now();
  requestAnimationFrame(tick);
}

window.kinemaViewer = { frame: 0, setFrame: () => {}, playing: false, ready: false, error: null, stats: frameStats() };
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
