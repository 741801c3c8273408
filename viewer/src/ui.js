// The controls' bar (play, the frame slider, the speed and colouring menus, the line saying
// what is shown) and the colour legend over the view's top right corner: made (buildUi), the
// menus set for the trajectory (fillMenus), the legend of the colouring chosen (showLegend).

import { LOW_END, legendValue, viridisCss } from "./colours.js";

const SPEEDS = [0.25, 0.5, 1, 2, 4];

export function buildUi(root, view) {
  const bar = document.createElement("div");
  bar.id = "kinema-ui";
  bar.innerHTML = `
    <button id="kinema-play" title="play / pause (space)">▶</button>
    <input id="kinema-scrub" type="range" min="0" max="0" value="0" step="1">
    <label>speed <select id="kinema-speed">${SPEEDS.map((s) => `<option value="${s}"${s === 1 ? " selected" : ""}>${s}×</option>`).join("")}</select></label>
    <label>colour <select id="kinema-colour"><option value="speed">speed</option><option value="id">id</option><option value="color">color</option><option value="none">none</option></select></label>
    <span id="kinema-info"></span>`;
  root.appendChild(bar);
  // The colour legend: what the colours mean, over the view's top right corner.
  const legend = document.createElement("div");
  legend.id = "kinema-legend";
  const stops = Array.from({ length: 11 }, (_, i) => `${viridisCss(LOW_END + ((1 - LOW_END) * i) / 10)} ${i * 10}%`).join(", ");
  legend.innerHTML = `<div id="kinema-legend-label"></div><div id="kinema-legend-bar" style="background: linear-gradient(to right, ${stops})"></div>
    <div id="kinema-legend-ticks"><span id="kinema-legend-min"></span><span id="kinema-legend-max"></span></div>`;
  view.appendChild(legend);
  const get = (id) => document.getElementById(id);
  return {
    play: get("kinema-play"),
    scrub: get("kinema-scrub"),
    speed: get("kinema-speed"),
    colour: get("kinema-colour"),
    info: get("kinema-info"),
    legend,
    legendLabel: get("kinema-legend-label"),
    legendMin: get("kinema-legend-min"),
    legendMax: get("kinema-legend-max"),
  };
}

// The menus for this trajectory: the slider over its frames, "speed" disabled without speeds,
// "color" only where offered (see buildParticles); the colouring the trajectory asks for (a
// scene's [render] color_by) chosen where the page has it, else speed (id when the speeds are
// unknown).
export function fillMenus(ui, meta, speed, offerOwn) {
  ui.scrub.max = String(meta.frames - 1);
  if (!speed) ui.colour.querySelector('option[value="speed"]').disabled = true;
  if (!offerOwn) ui.colour.querySelector('option[value="color"]').remove();
  const offered = (v) => Array.from(ui.colour.options).some((o) => o.value === v && !o.disabled);
  ui.colour.value = offered(meta.colorBy) ? meta.colorBy : speed ? "speed" : "id";
}

// The legend names what the colours show and the values at the ends of the ramp. Returns the
// legend shown ({label, min, max, integer}) or null (none for this colouring).
export function showLegend(ui, meta, colouring, speed) {
  let legendShown = null;
  if (colouring === "speed" && speed) legendShown = { label: "speed (m/s)", min: meta.speedMin, max: meta.speedMax };
  else if (colouring === "id") legendShown = { label: "particle id", min: meta.idRange[0], max: meta.idRange[1], integer: true };
  ui.legend.style.display = legendShown ? "" : "none";
  if (legendShown) {
    ui.legendLabel.textContent = legendShown.label;
    ui.legendMin.textContent = legendValue(legendShown.min, legendShown.integer);
    ui.legendMax.textContent = legendValue(legendShown.max, legendShown.integer);
  }
  return legendShown;
}
