// The springs: a line between the two ends' centres of each spring whose ends are both alive
// at the frame shown.

import * as THREE from "three";

const SPRING_COLOR = 0xa0a0a6; // springs: lighter than the outlines (scenery.js), to show on the dark background

// The springs (`springs`: int32 pairs of particle indices, or null) as `lines` (in the scene
// only when there are some: `count`), and fill(frame, aliveNow), which draws those between
// live ends at the frame's positions (`visible` of them).
export function buildSprings(springs, dim) {
  // Springs: a segment between the two ends' centres, while both are alive; the visible ones
  // are packed at the front of the buffer and the draw range cut to them.
  const springCount = springs ? springs.length / 2 : 0;
  const springPositions = new Float32Array(Math.max(springCount, 1) * 6);
  const springGeometry = new THREE.BufferGeometry();
  const springAttr = new THREE.BufferAttribute(springPositions, 3).setUsage(THREE.DynamicDrawUsage);
  springGeometry.setAttribute("position", springAttr);
  springGeometry.setDrawRange(0, 0);
  const springMaterial = new THREE.LineBasicMaterial({ color: SPRING_COLOR });
  if (dim === 2) {
    springMaterial.depthTest = false;
    springMaterial.depthWrite = false;
  }
  const springLines = new THREE.LineSegments(springGeometry, springMaterial);
  springLines.frustumCulled = false;
  springLines.renderOrder = -1;
  const drawn = {
    count: springCount,
    lines: springLines,
    visible: 0,
    fill(frame, aliveNow) {
      if (!springCount) return;
      let m = 0;
      for (let s = 0; s < springCount; s++) {
        const a = springs[2 * s];
        const b = springs[2 * s + 1];
        if (!aliveNow[a] || !aliveNow[b]) continue;
        springPositions.set(frame.subarray(3 * a, 3 * a + 3), 6 * m);
        springPositions.set(frame.subarray(3 * b, 3 * b + 3), 6 * m + 3);
        m++;
      }
      drawn.visible = m;
      springGeometry.setDrawRange(0, 2 * m);
      if (m > 0) {
        springAttr.addUpdateRange(0, 6 * m);
        springAttr.needsUpdate = true;
      }
    },
  };
  return drawn;
}
