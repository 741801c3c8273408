// Playback: the frame shown (setFrame: the colliders, particles, springs and colours at that
// frame, the slider and the line saying what is shown), playing and pausing, what the
// controls, keys, camera and window do, and the animation loop, which steps the frames in
// time and draws the scene when something changed. `v` is the viewer's record (see start in
// viewer.js).

import { pointScale, resize } from "./camera.js";
import { placeColliders } from "./scenery.js";
import { showLegend } from "./ui.js";

// Show frame k (rounded, within the trajectory); keepTime: the playback's time stays where it
// is (the animation loop's steps), else it moves to the frame's.
export function setFrame(v, k, keepTime = false) {
  const { frames, times, n, state, ui, particles } = v;
  k = Math.max(0, Math.min(frames - 1, Math.round(k)));
  if (k !== state.frame) {
    placeColliders(v.drawn, k);
    particles.place(k);
    particles.fillAlive(k);
    v.springs.fill(particles.position.array, particles.aliveNow);
    if (v.colouring === "speed") particles.fillColour(v.colouring, k); // id and none do not change with the frame
    state.stats.steps++;
    ui.scrub.value = String(k);
    const count = v.alive ? `${particles.visible.toLocaleString()} of ${n.toLocaleString()}` : n.toLocaleString();
    ui.info.textContent = `${count} ${n === 1 ? "particle" : "particles"} · t = ${times[k].toFixed(3)} s · frame ${k + 1}/${frames}${v.infoSuffix}`;
  }
  state.frame = k;
  if (!keepTime) v.playbackTime = times[k];
  v.dirty = true;
}

export function setPlaying(v, on) {
  v.state.playing = on && v.frames > 1;
  v.ui.play.textContent = v.state.playing ? "❚❚" : "▶";
}

// The legend of the colouring chosen (see showLegend).
export function setLegend(v) {
  v.legendShown = showLegend(v.ui, v.meta, v.colouring, v.speed);
}

// What the controls, the space key, the camera's controls and the window's size do.
export function listen(v) {
  const { ui, state, frames } = v;
  ui.play.addEventListener("click", () => {
    if (!state.playing && state.frame >= frames - 1) setFrame(v, 0);
    setPlaying(v, !state.playing);
  });
  ui.scrub.addEventListener("input", () => {
    setPlaying(v, false);
    setFrame(v, Number(ui.scrub.value));
  });
  ui.speed.addEventListener("change", () => (v.playbackSpeed = Number(ui.speed.value)));
  ui.colour.addEventListener("change", () => {
    v.colouring = ui.colour.value;
    v.particles.fillColour(v.colouring, state.frame);
    setLegend(v);
    v.dirty = true;
  });
  window.addEventListener("keydown", (e) => {
    if (e.code === "Space" && e.target.tagName !== "SELECT") {
      e.preventDefault();
      ui.play.click();
    }
  });
  v.cam.controls.addEventListener("change", () => {
    if (v.dim === 2) pointScale(v); // zooming an orthographic camera changes pixels per metre
    v.dirty = true;
  });
  window.addEventListener("resize", () => resize(v));
}

// The animation loop, from the next animation frame on: the turntable turned, the playback
// stepped, the scene drawn when something changed, the frame statistics counted.
export function animate(v) {
  const { frames, times, state, renderer, scene } = v;
  const { camera, controls } = v.cam;
  let last = performance.now();
  function tick(now) {
    const begun = performance.now();
    state.stats.tick(now - last);
    const elapsed = Math.min((now - last) / 1000, 0.25); // a hidden tab does not jump far ahead
    last = now;
    if (controls.autoRotate) controls.update(elapsed);
    if (state.playing) {
      // Real time times the chosen speed; the shown frame is the last one at or before it.
      v.playbackTime += elapsed * v.playbackSpeed;
      if (v.playbackTime >= v.loopEnd) v.playbackTime = times[0] + (v.playbackTime - v.loopEnd);
      let k = state.frame;
      if (times[k] > v.playbackTime) k = 0;
      while (k + 1 < frames && times[k + 1] <= v.playbackTime) k++;
      if (k !== state.frame) setFrame(v, k, true);
    }
    if (v.dirty) {
      renderer.render(scene, camera);
      v.dirty = false;
      state.stats.drew(performance.now() - begun);
    }
    requestAnimationFrame(tick);
  }
  requestAnimationFrame(tick);
}
