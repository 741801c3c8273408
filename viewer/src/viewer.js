//! kinema trajectory viewer: frames as THREE.Points with a sprite shader, the colliders and
//! springs, an orbit camera framing the scene, a colour legend and a small UI.
//
// The entry point (viewer/build.mjs bundles it with what it imports): it loads the page's
// data, builds the scene and the controls (start) and keeps window.kinemaViewer. The parts:
//   data.js       the page's data (the trajectory's metadata and arrays) and the URL hash's options
//   scenery.js    the colliders drawn, in the renderer's neutral colours; vec, boxCorners
//   particles.js  the particles as THREE.Points, their colouring
//   springs.js    the springs as lines between live ends
//   shaders.js    the GLSL of the particles, sphere obstacles and meshes
//   colours.js    viridis (the "speed" and "id" colourings) and the legend's values
//   camera.js     the camera fitted to the scene or the scene's own, the orbit above the floor, the canvas's size
//   ui.js         the controls' bar, the colour legend, the menus
//   playback.js   the frame shown, playing, the controls' listeners, the animation loop
//   describe.js   window.kinemaViewer.info(): what is drawn, for the tests
//   stats.js      the frame statistics
//
// Drawn: the particles alive at the frame (the others are moved out of the clip volume by
// the vertex shader); springs as lines between live ends; the colliders (see scenery.js);
// seen by a camera fitted to the scene or the scene's own (see camera.js).
//
// `window.kinemaViewer` is the page's state for tests and benchmarks: `ready`, `error`,
// `frame` (the trajectory frame shown), `playing`, `setFrame(k)`, `stats`, the frame
// statistics (see frameStats in stats.js): `stats.snapshot()` gives animation frames run, frames drawn,
// trajectory frames stepped and median frame times in ms over the last STATS_WINDOW frames;
// `info()`, a read-only description of what is drawn (see `describe` in describe.js: the colouring,
// the legend, the orbit camera and its floor, ...); and `ownColours()`, the RGB bytes "color"
// gives each particle, read from the colour buffer drawn (see `ownColourBytes` in particles.js).

import * as THREE from "three";
import { buildCamera, framing, resize } from "./camera.js";
import { hashOptions, loadData } from "./data.js";
import { describe } from "./describe.js";
import { buildParticles } from "./particles.js";
import { animate, listen, setFrame, setLegend, setPlaying } from "./playback.js";
import { buildScenery } from "./scenery.js";
import { buildSprings } from "./springs.js";
import { frameStats } from "./stats.js";
import { buildUi, fillMenus } from "./ui.js";

const BACKGROUND = 0x101014;

// The viewer for the loaded data (see loadData): the renderer on the page's #kinema-view, the
// scene (the colliders, the particles, the springs), the camera, the controls, then the first
// frame drawn and the animation loop started. What the parts share is one record, `v`: the
// trajectory's `meta`, `n`, `frames`, `times`, `dim` and its `speed` and `alive` arrays (or
// null), the `container`, `renderer` and `scene`, what was built (`drawn`: the colliders,
// `cam`, `particles`, `springs`, `ui`), `state` (window.kinemaViewer) and the playback's state:
// the `colouring` chosen, `playbackSpeed`, `playbackTime` and `loopEnd`, `dirty` (the scene
// is drawn at the next animation frame), `infoSuffix` and the `legendShown`.
function start(data) {
  const { meta } = data;
  const frames = meta.frames;
  const times = meta.t;
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
  const cam = buildCamera(meta, renderer, drawn, box);
  const particles = buildParticles(meta, data, box.centre, box.extent);
  scene.add(particles.points);
  const springs = buildSprings(data.springs, meta.dim);
  if (springs.count) scene.add(springs.lines);

  const ui = buildUi(document.body, container);
  fillMenus(ui, meta, data.speed, particles.offerOwn);

  const v = {
    meta,
    n: meta.n,
    frames,
    times,
    dim: meta.dim,
    speed: data.speed,
    alive: data.alive,
    container,
    renderer,
    scene,
    drawn,
    cam,
    particles,
    springs,
    ui,
    state: window.kinemaViewer,
    colouring: ui.colour.value,
    playbackSpeed: Number(ui.speed.value),
    playbackTime: times[0],
    // Playback loops from the first frame to one frame interval past the last, so that the last
    // frame is shown as long as the others before the first comes round again.
    loopEnd: frames > 1 ? 2 * times[frames - 1] - times[frames - 2] : times[0],
    dirty: true,
    infoSuffix: meta.note ? ` · ${meta.note}` : "",
    legendShown: null,
  };
  listen(v);

  const state = v.state;
  const opts = hashOptions();
  state.frame = -1;
  state.setFrame = (k) => {
    setPlaying(v, false);
    setFrame(v, k);
    renderer.render(scene, cam.camera);
  };
  state.info = () => describe(v);
  state.ownColours = particles.ownColourBytes;
  resize(v);
  particles.fillColour(v.colouring, 0);
  setLegend(v);
  setFrame(v, opts.frame ?? 0);
  setPlaying(v, opts.frame === null || opts.play);
  cam.controls.autoRotate = opts.rotate;
  renderer.render(scene, cam.camera);
  state.stats.reset();
  state.ready = true;
  animate(v);
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
