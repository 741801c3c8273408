// The page's data: the trajectory's metadata and arrays, read from the page or the file
// beside it, and the options of the URL hash.
//
// The page carries `<script type="application/json" id="kinema-data">` with the metadata
// written by python/kinema/viewer: n (particles), frames, dim, t (times, s), bounds
// {min, max} (m, the particles), extent {min, max} (m: the live particles with their radii
// over every frame and the colliders' finite parts, a moving one's wherever it goes),
// colliders (plain descriptions, 3 values per vector, ±inf bounds as null; a moving one with
// `poses`, base64 little-endian float32, a 4×4 matrix per frame in column-major order: where
// it is at that frame's time, x = M x₀ for a point x₀ of it as described), speedMin/speedMax (m/s, over the live particles of the
// frames shown), idRange (the lowest and highest id shown), springCount, aliveBytes,
// defaultRadius, note, colorBy (the colouring to open with: "speed", "id", "color", "none" or
// null), noOwnColor (RGB bytes: what "color" draws a particle without its own colour in, the
// renderer's NO_OWN_COLOR), camera (the view to open with, a scene's [render] camera, or
// null: {type: "3d", eye, target, up, fovDeg} or {type: "2d", view: [xmin, ymin, xmax,
// ymax]}), and either base64 blobs
// (positions, speed, radii: little-endian float32; springs: int32 column pairs; alive: per
// frame aliveBytes bytes, bit i of byte j for particle 8 j + i, absent when every particle is
// alive throughout; colors: RGBA bytes per particle, alpha 0 for none) or `source` naming a
// binary file served beside the page whose layout is given by `layout` ([byte offset,
// element count] of each, null for what is absent).
//
// A URL hash `#frame=K` opens paused at frame K (used by the tests); `#frame=K&play=1` plays;
// `rotate=1` turns the orbit camera about its target (a turntable; the benchmark draws every
// animation frame that way).

export function decodeBase64(text) {
  const bin = atob(text);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}

const ARRAYS = { positions: Float32Array, speed: Float32Array, radii: Float32Array, springs: Int32Array, alive: Uint8Array, colors: Uint8Array };

export async function loadData() {
  const meta = JSON.parse(document.getElementById("kinema-data").textContent);
  const data = { meta };
  if (meta.source) {
    const response = await fetch(meta.source);
    if (!response.ok) throw new Error(`${meta.source}: HTTP ${response.status}`);
    const buffer = await response.arrayBuffer();
    for (const [name, Type] of Object.entries(ARRAYS)) {
      const entry = meta.layout[name];
      data[name] = entry ? new Type(buffer, entry[0], entry[1]) : null;
    }
    return data;
  }
  for (const [name, Type] of Object.entries(ARRAYS)) data[name] = meta[name] ? new Type(decodeBase64(meta[name])) : null;
  return data;
}

export function hashOptions() {
  const params = new URLSearchParams(location.hash.slice(1));
  const frame = params.has("frame") ? parseInt(params.get("frame"), 10) : null;
  return { frame: Number.isFinite(frame) ? frame : null, play: params.get("play") === "1", rotate: params.get("rotate") === "1" };
}
