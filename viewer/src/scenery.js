// The colliders as three.js objects (buildScenery), in the neutral colours of kinema's own
// renderer, and the geometry the viewer shares (vec, boxCorners).
//
// Planes as a floor patch (3D) or a line with its solid side filled (2D); boxes as their
// edges less those of open faces, with the walls of open faces reaching the extent, and a
// floor face; sphere obstacles as shaded spheres (3D) or discs (2D); triangle meshes (3D) as
// a translucent lit surface seen from both sides, with its rim and creases as lines, so that
// what is inside shows. A moving collider's objects sit in a group of their own whose matrix
// is set to its pose at the frame shown (planes, boxes, spheres and meshes alike).

import * as THREE from "three";
import { LineSegments2 } from "three/examples/jsm/lines/LineSegments2.js";
import { LineSegmentsGeometry } from "three/examples/jsm/lines/LineSegmentsGeometry.js";
import { LineMaterial } from "three/examples/jsm/lines/LineMaterial.js";
import { decodeBase64 } from "./data.js";
import { MESH_FRAGMENT, MESH_VERTEX, OBSTACLE_FRAGMENT, OBSTACLE_VERTEX } from "./shaders.js";

// The scenery's neutral colours, those of kinema's own renderer (crates/kinema/src/render/
// scenery.rs), so that the particles' colours keep their meaning.
const FLOOR_COLOR = 0xe0e0dc; // (224, 224, 220): plane floor patches, the solid side of 2D planes
const BOX_FLOOR_COLOR = 0xd4d4ce; // (212, 212, 206): a box's floor face
const LINE_COLOR = 0x606064; // (96, 96, 100): outlines, grid lines (faint), box edges, 2D plane lines
const OBSTACLE_RGB = [176 / 255, 178 / 255, 184 / 255]; // sphere obstacles, shaded like the particles
// Triangle meshes: a light grey at MESH_OPACITY (the renderer's PLANE_ALPHA), lit as the
// renderer's facets (MESH_AMBIENT of the colour where the light does not reach), without
// writing depth (what is inside or behind shows through); its rim and the edges where its
// faces meet at more than MESH_CREASE_DEG as lines.
const MESH_RGB = [200 / 255, 200 / 255, 196 / 255];
const MESH_OPACITY = 0.3;
const MESH_AMBIENT = 0.45;
const MESH_EDGE_COLOR = 0xa0a0a6;
const MESH_EDGE_OPACITY = 0.6;
const MESH_CREASE_DEG = 30;
// Line widths, CSS pixels (as the renderer's).
const PATCH_OUTLINE_PX = 1.5;
const BOX_EDGE_PX = 1.5;
const PLANE_2D_PX = 3;
const BOX_2D_PX = 2;
const GRID_ALPHA = 0.25;
const FLOOR_TILT = Math.PI / 3; // a plane facing up within this of level is a floor the 3D orbit stays above

// The smallest of 1, 2, 5 × 10^k not below x (x > 0).
function niceStep(x) {
  const p = 10 ** Math.floor(Math.log10(x));
  const m = x / p;
  return p * (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10);
}

export const vec = (a) => new THREE.Vector3(a[0], a[1], a[2]);

// The 8 corners of the box [lo, hi].
export function boxCorners(lo, hi) {
  const out = [];
  for (let i = 0; i < 8; i++) out.push(new THREE.Vector3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z));
  return out;
}

// What buildScenery draws with and tallies: the extent (elo, ehi, its centre and diagonal),
// what it returns (see there; `floor` through floorAt) and the makers of the objects, which
// put them into `holder`, the group of the collider being built. In 2D the scenery lies under
// everything, drawn first without depth (`flat`).
function sceneryDrawing(meta, group) {
  const dim = meta.dim;
  const elo = vec(meta.extent.min);
  const ehi = vec(meta.extent.max);
  const ecentre = elo.clone().add(ehi).multiplyScalar(0.5);
  const esize = Math.max(ehi.clone().sub(elo).length(), 1e-9);
  const drawing = {
    dim,
    elo,
    ehi,
    ecentre,
    esize,
    counts: { plane: 0, box: 0, sphere: 0, mesh: 0 },
    meshes: [],
    corners: [],
    floor: null,
    lineMaterials: [],
    moving: [],
    boxEdges: 0,
    holder: group, // where the collider being built puts its objects
  };
  drawing.floorAt = (z) => (drawing.floor = drawing.floor === null ? z : Math.min(drawing.floor, z));
  drawing.flat = (material, order = -2) => {
    if (dim === 2) {
      material.depthTest = false;
      material.depthWrite = false;
    }
    return [material, order];
  };
  drawing.add = (object, [material, order]) => {
    object.material = material;
    if (dim === 2) object.renderOrder = order;
    drawing.holder.add(object);
    return object;
  };
  drawing.fatLines = (points, width) => {
    // points: [a0, b0, a1, b1, ...] Vector3s; drawn `width` CSS pixels wide.
    const geometry = new LineSegmentsGeometry().setPositions(points.flatMap((p) => [p.x, p.y, p.z]));
    const material = new LineMaterial({ color: LINE_COLOR, linewidth: width });
    drawing.lineMaterials.push(material);
    const lines = new LineSegments2(geometry);
    drawing.add(lines, drawing.flat(material, -1));
    return lines;
  };
  drawing.quad = (a, b, c, d, color, opacity = 1) => {
    const geometry = new THREE.BufferGeometry().setFromPoints([a, b, c, a, c, d]);
    const material = new THREE.MeshBasicMaterial({ color, side: THREE.DoubleSide, transparent: opacity < 1, opacity });
    // Lines on the face (grid, outline, edges) win the depth test against it.
    material.polygonOffset = true;
    material.polygonOffsetFactor = 1;
    material.polygonOffsetUnits = 1;
    return drawing.add(new THREE.Mesh(geometry), drawing.flat(material, -3));
  };
  return drawing;
}

// A plane in 2D: the line n·(q − p) = 0 of the normal's xy part, its solid side (against the
// normal) lightly filled, both reaching far past the scene.
function drawPlaneLine(drawing, c) {
  const { ecentre, esize, counts, quad, fatLines } = drawing;
  const p = vec(c.point);
  const nxy = new THREE.Vector3(c.normal[0], c.normal[1], 0);
  if (nxy.length() <= 1e-9 * vec(c.normal).length()) return;
  nxy.normalize();
  const t = new THREE.Vector3(-nxy.y, nxy.x, 0);
  const foot = new THREE.Vector3(p.x, p.y, 0).addScaledVector(t, t.dot(ecentre.clone().sub(p)));
  const reach = 1000 * esize;
  const a = foot.clone().addScaledVector(t, -reach);
  const b = foot.clone().addScaledVector(t, reach);
  quad(a, b, b.clone().addScaledVector(nxy, -reach), a.clone().addScaledVector(nxy, -reach), FLOOR_COLOR, 0.3);
  fatLines([a, b], PLANE_2D_PX);
  counts.plane++;
}

// A plane in 3D: a floor patch with its grid and outline.
function drawFloorPatch(drawing, c) {
  const { elo, ehi, counts, corners, add, quad, fatLines, floorAt } = drawing;
  const n = vec(c.normal).normalize();
  const p = vec(c.point);
  // A finite floor patch under the scene: the extent's box projected on the plane (along
  // tangents t1, t2: for a horizontal floor, x and y), each side at least 0.6 of the
  // longer one, widened by 0.15 of the longer one all round.
  const k = [0, 1, 2].reduce((best, i) => (Math.abs(n.getComponent(i)) < Math.abs(n.getComponent(best)) ? i : best), 0);
  const axis = new THREE.Vector3().setComponent(k, 1);
  const t1 = new THREE.Vector3().crossVectors(n, axis).normalize();
  const t2 = new THREE.Vector3().crossVectors(n, t1);
  const range = [
    [Infinity, -Infinity],
    [Infinity, -Infinity],
  ];
  for (const q of boxCorners(elo, ehi)) {
    const d = q.clone().sub(p);
    [d.dot(t1), d.dot(t2)].forEach((x, i) => {
      range[i][0] = Math.min(range[i][0], x);
      range[i][1] = Math.max(range[i][1], x);
    });
  }
  const longest = Math.max(range[0][1] - range[0][0], range[1][1] - range[1][0], 1e-9);
  for (const r of range) {
    const mid = 0.5 * (r[0] + r[1]);
    const half = 0.5 * Math.max(r[1] - r[0], 0.6 * longest) + 0.15 * longest;
    r[0] = mid - half;
    r[1] = mid + half;
  }
  const at = (u, v) => p.clone().addScaledVector(t1, u).addScaledVector(t2, v);
  const [[u0, u1], [v0, v1]] = range;
  const patch = [at(u0, v0), at(u1, v0), at(u1, v1), at(u0, v1)];
  quad(...patch, FLOOR_COLOR);
  // The grid: lines on multiples of a 1-2-5 step (counted from the plane's point, so
  // that they stay put), about 10 to 25 across the patch.
  const step = niceStep(longest / 10);
  const grid = [];
  for (let u = Math.ceil(u0 / step) * step; u < u1 - 1e-9 * step; u += step) if (u > u0 + 1e-9 * step) grid.push(at(u, v0), at(u, v1));
  for (let v = Math.ceil(v0 / step) * step; v < v1 - 1e-9 * step; v += step) if (v > v0 + 1e-9 * step) grid.push(at(u0, v), at(u1, v));
  const gridMaterial = new THREE.LineBasicMaterial({ color: LINE_COLOR, transparent: true, opacity: GRID_ALPHA, depthWrite: false });
  add(new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(grid)), [gridMaterial, -2]);
  fatLines([0, 1, 1, 2, 2, 3, 3, 0].map((i) => patch[i]), PATCH_OUTLINE_PX);
  corners.push(...patch);
  if (n.z > Math.cos(FLOOR_TILT)) floorAt(Math.min(...patch.map((q) => q.z)));
  counts.plane++;
}

// A box: its edges (3D) or sides (2D) where its faces are closed, and its floor face (3D).
function drawBox(drawing, c) {
  const { dim, elo, ehi, counts, corners, quad, fatLines, floorAt } = drawing;
  // Open bounds (null) reach the extent (never past the other bound).
  const lo = [0, 1, 2].map((k) => c.lo[k] ?? (c.hi[k] !== null ? Math.min(elo.getComponent(k), c.hi[k]) : elo.getComponent(k)));
  const hi = [0, 1, 2].map((k) => c.hi[k] ?? Math.max(ehi.getComponent(k), lo[k]));
  const corner = (s) => new THREE.Vector3(...[0, 1, 2].map((k) => (s[k] ? hi[k] : lo[k])));
  const finite = (k, high) => (high ? c.hi[k] : c.lo[k]) !== null;
  const segments = [];
  if (dim === 2) {
    // Each side where its own bound is finite.
    const z = 0;
    const p = (x, y) => new THREE.Vector3(x, y, z);
    if (finite(0, false)) segments.push(p(lo[0], lo[1]), p(lo[0], hi[1]));
    if (finite(0, true)) segments.push(p(hi[0], lo[1]), p(hi[0], hi[1]));
    if (finite(1, false)) segments.push(p(lo[0], lo[1]), p(hi[0], lo[1]));
    if (finite(1, true)) segments.push(p(lo[0], hi[1]), p(hi[0], hi[1]));
    corners.push(p(lo[0], lo[1]), p(hi[0], lo[1]), p(hi[0], hi[1]), p(lo[0], hi[1]));
  } else {
    // An edge along `axis` lies on two faces: it is drawn when both are closed (an open
    // top has no rim; the walls rise to the extent).
    for (let axis = 0; axis < 3; axis++) {
      const b = (axis + 1) % 3;
      const cc = (axis + 2) % 3;
      for (const [sb, sc] of [
        [false, false],
        [true, false],
        [false, true],
        [true, true],
      ]) {
        if (!finite(b, sb) || !finite(cc, sc)) continue;
        const s0 = [false, false, false];
        s0[b] = sb;
        s0[cc] = sc;
        const s1 = s0.slice();
        s1[axis] = true;
        segments.push(corner(s0), corner(s1));
      }
    }
    // The floor: the lower z face, lightly filled, when it is closed.
    if (finite(2, false)) {
      quad(corner([0, 0, 0]), corner([1, 0, 0]), corner([1, 1, 0]), corner([0, 1, 0]), BOX_FLOOR_COLOR);
      floorAt(lo[2]);
    }
    corners.push(...boxCorners(corner([0, 0, 0]), corner([1, 1, 1])));
  }
  if (segments.length) fatLines(segments, dim === 2 ? BOX_2D_PX : BOX_EDGE_PX);
  drawing.boxEdges += segments.length / 2;
  counts.box++;
}

// A sphere obstacle: a shaded sphere (3D) or a disc (2D).
function drawSphere(drawing, c) {
  const { dim, counts, corners, add, flat } = drawing;
  const centre = vec(c.center);
  const r = c.radius;
  if (dim === 2) {
    const disc = add(new THREE.Mesh(new THREE.CircleGeometry(r, 96)), flat(new THREE.MeshBasicMaterial({ color: new THREE.Color().setRGB(...OBSTACLE_RGB, THREE.SRGBColorSpace) })));
    disc.position.set(centre.x, centre.y, 0);
    corners.push(...boxCorners(new THREE.Vector3(centre.x - r, centre.y - r, 0), new THREE.Vector3(centre.x + r, centre.y + r, 0)));
  } else {
    const material = new THREE.ShaderMaterial({ uniforms: { uColor: { value: new THREE.Vector3(...OBSTACLE_RGB) } }, vertexShader: OBSTACLE_VERTEX, fragmentShader: OBSTACLE_FRAGMENT });
    const ball = add(new THREE.Mesh(new THREE.SphereGeometry(r, 64, 32)), [material, 0]);
    ball.position.copy(centre);
    const d = new THREE.Vector3(r, r, r);
    corners.push(...boxCorners(centre.clone().sub(d), centre.clone().add(d)));
  }
  counts.sphere++;
}

// A triangle mesh (3D): its translucent surface and its rim and creases as lines.
function drawMesh(drawing, c) {
  const { counts, corners, meshes, add } = drawing;
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(decodeBase64(c.vertices)), 3));
  geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(decodeBase64(c.faces)), 1));
  const material = new THREE.ShaderMaterial({
    uniforms: { uColor: { value: new THREE.Vector3(...MESH_RGB) }, uOpacity: { value: MESH_OPACITY }, uAmbient: { value: MESH_AMBIENT } },
    vertexShader: MESH_VERTEX,
    fragmentShader: MESH_FRAGMENT,
    transparent: true,
    depthWrite: false,
    side: THREE.DoubleSide,
  });
  const surface = add(new THREE.Mesh(geometry), [material, 0]);
  surface.name = "kinema-mesh";
  // The rim (edges of one triangle) and the creases, drawn over the surface.
  const edges = new THREE.EdgesGeometry(geometry, MESH_CREASE_DEG);
  const edgeMaterial = new THREE.LineBasicMaterial({ color: MESH_EDGE_COLOR, transparent: true, opacity: MESH_EDGE_OPACITY, depthWrite: false });
  add(new THREE.LineSegments(edges), [edgeMaterial, 0]);
  meshes.push({
    triangles: geometry.index.count / 3,
    edges: edges.attributes.position.count / 2,
    opacity: material.uniforms.uOpacity.value,
    transparent: material.transparent,
    depthWrite: material.depthWrite,
    doubleSided: material.side === THREE.DoubleSide,
  });
  corners.push(...boxCorners(vec(c.lo), vec(c.hi)));
  counts.mesh++;
}

// One collider's objects, into `drawing.holder`.
function buildCollider(drawing, c) {
  if (c.type === "plane") (drawing.dim === 2 ? drawPlaneLine : drawFloorPatch)(drawing, c);
  else if (c.type === "box") drawBox(drawing, c);
  else if (c.type === "sphere") drawSphere(drawing, c);
  else if (c.type === "mesh" && drawing.dim !== 2) drawMesh(drawing, c);
}

// The colliders as three.js objects in `group`. Returns what was drawn: `counts` (objects by
// type: a plane's floor patch or 2D line, a box, a sphere, a mesh), `boxEdges` (box edges in
// 3D, sides in 2D), `meshes` (per mesh: its triangles and edge lines drawn and its surface's
// material: opacity, depthWrite, double-sided), `corners` (the finite corners of what was
// drawn: floor patches, boxes with their open bounds at the extent, spheres' and meshes'
// bounding boxes; the camera frames them), `moving` (per moving collider: its type, the group
// holding its objects, its poses and the indices of its corners in `corners`),
// `lineMaterials` (their resolution follows the canvas) and `floor` (3D: the height of the
// lowest floor, null without one: a plane facing up, less than FLOOR_TILT from level, at its
// patch's lowest corner, or a box's closed bottom).
export function buildScenery(meta, group) {
  const drawing = sceneryDrawing(meta, group);
  const { corners, moving } = drawing;
  for (const c of meta.colliders || []) {
    drawing.holder = group;
    let mover = null;
    if (c.poses) {
      // A moving collider: drawn as described, in a group placed at each frame's pose.
      drawing.holder = new THREE.Group();
      drawing.holder.matrixAutoUpdate = false;
      group.add(drawing.holder);
      mover = { type: c.type, group: drawing.holder, poses: new Float32Array(decodeBase64(c.poses)), first: corners.length, end: corners.length };
      moving.push(mover);
    }
    buildCollider(drawing, c);
    if (mover) mover.end = corners.length;
  }
  const { counts, boxEdges, meshes, lineMaterials, floor } = drawing;
  return { counts, boxEdges, meshes, corners, lineMaterials, floor, moving };
}

// Moving colliders where they are at frame k: each one's group takes its pose.
export function placeColliders(drawn, k) {
  for (const m of drawn.moving) {
    m.group.matrix.fromArray(m.poses, 16 * k);
    m.group.matrixWorldNeedsUpdate = true;
  }
}
