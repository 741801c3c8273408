// The colour map the "speed" and "id" colourings use (viridis, from LOW_END up), in the
// shaders' polynomial and as CSS colours for the legend's gradient, and how the legend writes
// its values.
//
// Colourings (the menu): "speed" and "id" through viridis with a legend of the real least and
// greatest values shown, "color" each particle's own colour (noOwnColor where it has none;
// offered when some particle has one or colorBy asks for it), "none" one plain colour.

// Viridis by a degree-6 polynomial fit per channel (good to about 1/255 of the table); the
// legend's gradient evaluates the same polynomial.
export const VIRIDIS = [
  [0.2777273272234177, 0.005407344544966578, 0.3340998053353061],
  [0.1050930431085774, 1.404613529898575, 1.384590162594685],
  [-0.3308618287255563, 0.214847559468213, 0.09509516302823659],
  [-4.634230498983486, -5.799100973351585, -19.33244095627987],
  [6.228269936347081, 14.17993336680509, 56.69055260068105],
  [4.776384997670288, -13.74514537774601, -65.35303263337234],
  [-5.435455855934631, 4.645852612178535, 26.3124352495832],
];

// Where on viridis the lowest value sits: its bottom colour (luma 30) is near black on the
// page's near-black background, so the values use the map from 0.25 up (steel blue), as
// kinema's renderer does (kinema.render.low_end("viridis")); the legend shows that part.
export const LOW_END = 0.25;

export function viridisCss(t) {
  const c = [0, 1, 2].map((ch) => VIRIDIS.reduceRight((acc, coeffs) => acc * t + coeffs[ch], 0));
  return `rgb(${c.map((x) => Math.round(255 * Math.min(1, Math.max(0, x)))).join(",")})`;
}

// A value for the legend: an integer (ids) exactly; otherwise three significant digits (as
// the renderer's legend) but never fewer than the integer digits (1249.7 is 1250, not 1.25e3),
// no trailing zeros.
export function legendValue(x, integer = false) {
  x = Number(x);
  if (integer || Math.abs(x) >= 100) return String(Math.round(x));
  return String(Number(x.toPrecision(3)));
}
