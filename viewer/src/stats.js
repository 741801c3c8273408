// The frame statistics window.kinemaViewer.stats holds for tests and benchmarks (see
// frameStats).

const STATS_WINDOW = 120; // animation frames the medians are taken over (2 s at 60 Hz)

// Counters and the last STATS_WINDOW frame times in rings (no allocation per frame); the
// medians are computed when read. Times in ms: `frameMs`, between consecutive animation
// frames (1000 / frameMs is the frame rate the page reaches, at most the display's);
// `drawMs`, the script's work in the frames that drew (setting the frame and rendering:
// the GPU's work is not in it). A median is null before any frame was measured.
export function frameStats() {
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
