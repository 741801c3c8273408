//! The springs' force pass: each spring's force on its first end (springs in lanes, so that
//! the square roots and divisions of several springs go in one vector instruction), then each
//! particle's sum over the springs it ends, in spring order.
//!
//! Both passes run on all threads in chunks of a fixed size, and each particle's sum is the
//! same additions in the same order as one loop over the springs that adds F_i to end i and
//! subtracts it from end j: the result is the same for any number of threads, and the same
//! bits as that loop.

use rayon::prelude::*;

/// Springs (or particles) per chunk of the parallel passes (fixed, so the work is split the
/// same way for any number of threads).
const CHUNK: usize = 4096;

/// What the pass reads of the springs: ends, stiffness (N/m), rest length (m) and dashpot
/// coefficient (N·s/m), one per spring.
pub(super) struct SpringArrays<'a> {
    pub i: &'a [usize],
    pub j: &'a [usize],
    pub k: &'a [f64],
    pub rest_length: &'a [f64],
    pub damping: &'a [f64],
}

/// The force pass's buffers: each spring's force on its end i, N, with a fourth entry 1 (0
/// for a spring of zero length, which has no direction and adds nothing); and for each
/// particle the springs it ends, in spring order (`spring << 1 | 1` where it is the end j),
/// compressed by particle (`start`, `ends`).
#[derive(Debug, Clone, Default)]
pub(super) struct Scratch {
    tension: Vec<[f64; 4]>,
    start: Vec<u32>,
    ends: Vec<u32>,
}

impl PartialEq for Scratch {
    fn eq(&self, _: &Self) -> bool {
        true // buffers, not data
    }
}

impl Scratch {
    /// Adds F_i = [k (L − L₀) + c (u·n)] n to each spring's first end and −F_i to its second
    /// in `f` (N, 3 per particle; `x`, `v` in m and m/s, 3 per particle, every index of
    /// `springs` below their particle count).
    pub(super) fn accumulate(&mut self, springs: &SpringArrays, x: &[f64], v: &[f64], f: &mut [f64]) {
        let n = x.len() / 3;
        if self.start.len() != n + 1 {
            self.index_ends(springs, n);
        }
        self.tension.resize(springs.i.len(), [0.0; 4]);
        self.tension.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
            tension_chunk(springs, c * CHUNK, x, v, out);
        });
        let Scratch { tension, start, ends } = &*self;
        f.par_chunks_mut(3 * CHUNK).enumerate().for_each(|(c, fc)| {
            for (l, p) in (c * CHUNK..).take(fc.len() / 3).enumerate() {
                let mut sum = [fc[3 * l], fc[3 * l + 1], fc[3 * l + 2]];
                for &e in &ends[start[p] as usize..start[p + 1] as usize] {
                    let g = &tension[(e >> 1) as usize];
                    if g[3] == 0.0 {
                        continue; // coincident ends: no force
                    }
                    // sum − g as sum + (−g), the same number (IEEE 754 defines the difference
                    // so, signed zeros included); the sign bit flipped where p is the end j
                    let flip = u64::from(e & 1) << 63;
                    for q in 0..3 {
                        sum[q] += f64::from_bits(g[q].to_bits() ^ flip);
                    }
                }
                fc[3 * l..3 * l + 3].copy_from_slice(&sum);
            }
        });
    }

    /// For each of `n` particles, the springs it ends, in spring order (a counting sort by
    /// particle, stable): `start` and `ends`.
    fn index_ends(&mut self, springs: &SpringArrays, n: usize) {
        let (start, ends) = (&mut self.start, &mut self.ends);
        start.clear();
        start.resize(n + 1, 0);
        for p in springs.i.iter().chain(springs.j) {
            start[p + 1] += 1;
        }
        for p in 1..=n {
            start[p] += start[p - 1];
        }
        let mut next: Vec<u32> = start[..n].to_vec();
        ends.clear();
        ends.resize(2 * springs.i.len(), 0);
        for sp in 0..springs.i.len() {
            for (end, p) in [(0, springs.i[sp]), (1, springs.j[sp])] {
                ends[next[p] as usize] = (sp as u32) << 1 | end;
                next[p] += 1;
            }
        }
    }
}

/// The tension pass over the springs `first..first + out.len()`: [`avx::tension_chunk`]
/// where the machine has AVX (chosen at run time), [`tension_lanes`] elsewhere; the same
/// bits either way.
fn tension_chunk(springs: &SpringArrays, first: usize, x: &[f64], v: &[f64], out: &mut [[f64; 4]]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the machine has AVX (checked just above).
        unsafe { avx::tension_chunk(springs, first, x, v, out) };
        return;
    }
    tension_lanes(springs, first, x, v, out, |lanes, springs, s, block| {
        lanes.tension(0, springs, s, block)
    });
}

/// The tension pass in blocks of [`LANES`] springs: each block's differences gathered
/// (`Lanes::gather`), then their forces computed by `tension` (a [`Lanes::tension`]).
#[inline(always)]
fn tension_lanes(
    springs: &SpringArrays,
    first: usize,
    x: &[f64],
    v: &[f64],
    out: &mut [[f64; 4]],
    tension: impl Fn(&Lanes, &SpringArrays, usize, &mut [[f64; 4]]),
) {
    let mut lanes = Lanes {
        d: [[0.0; LANES]; 3],
        u: [[0.0; LANES]; 3],
    };
    for (b, block) in out.chunks_mut(LANES).enumerate() {
        let s = first + b * LANES;
        lanes.gather(springs, s, x, v, block.len());
        tension(&lanes, springs, s, block);
    }
}

/// Springs gathered, then computed side by side, in the tension pass (a multiple of 4, the
/// f64 of an AVX vector; the gathered block is read back long after it was written, so the
/// vector loads need not wait for the scalar stores).
const LANES: usize = 64;

/// The differences d = x_j − x_i and u = v_j − v_i of [`LANES`] springs, coordinate by
/// coordinate (structure of arrays, as the vector registers take them).
struct Lanes {
    d: [[f64; LANES]; 3],
    u: [[f64; LANES]; 3],
}

impl Lanes {
    /// d and u of springs `s..s + count` (count ≤ [`LANES`]).
    #[inline(always)]
    fn gather(&mut self, springs: &SpringArrays, s: usize, x: &[f64], v: &[f64], count: usize) {
        for l in 0..count {
            let (a, b) = (3 * springs.i[s + l], 3 * springs.j[s + l]);
            let (xa, xb) = (&x[a..a + 3], &x[b..b + 3]);
            let (va, vb) = (&v[a..a + 3], &v[b..b + 3]);
            for q in 0..3 {
                self.d[q][l] = xb[q] - xa[q];
                self.u[q][l] = vb[q] - va[q];
            }
        }
    }

    /// The force on end i of springs `s..s + out.len()` (lanes `from..`, as gathered), into
    /// `out` (with the fourth entry: 1, or 0 for coincident ends). With
    /// L = |d| = √((d_x² + d_y²) + d_z²) and n = d / L:
    /// F_i = [k (L − L₀) + c ((u_x n_x + u_y n_y) + u_z n_z)] n, in exactly these operations
    /// (the order of `vec3::dot`); [`avx::tension4`] does the same ones four lanes at a time.
    #[inline(always)]
    fn tension(&self, from: usize, springs: &SpringArrays, s: usize, out: &mut [[f64; 4]]) {
        let (d, u) = (&self.d, &self.u);
        for (m, o) in out.iter_mut().enumerate() {
            let (k, rest, c) = (springs.k[s + m], springs.rest_length[s + m], springs.damping[s + m]);
            let l = from + m;
            let len = (d[0][l] * d[0][l] + d[1][l] * d[1][l] + d[2][l] * d[2][l]).sqrt();
            let n = [d[0][l] / len, d[1][l] / len, d[2][l] / len];
            let along = u[0][l] * n[0] + u[1][l] * n[1] + u[2][l] * n[2];
            let tension = k * (len - rest) + c * along;
            *o = if len > 0.0 {
                [tension * n[0], tension * n[1], tension * n[2], 1.0]
            } else {
                [0.0; 4]
            };
        }
    }
}

/// The tension pass with AVX: [`Lanes::tension`] on four springs at once, the same IEEE
/// operations in the same order lane by lane (vector square roots and divisions are
/// correctly rounded like scalar ones, and no multiply-add is fused), so the same bits.
#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{tension_lanes, Lanes, SpringArrays};
    use std::arch::x86_64::*;

    /// [`super::tension_chunk`], compiled for AVX: blocks of four springs by [`tension4`],
    /// the few left of a block one by one.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn tension_chunk(springs: &SpringArrays, first: usize, x: &[f64], v: &[f64], out: &mut [[f64; 4]]) {
        tension_lanes(springs, first, x, v, out, |lanes, springs, s, block| {
            let done = block.len() / 4 * 4;
            let (quads, rest) = block.split_at_mut(done);
            for (q, quad) in quads.chunks_exact_mut(4).enumerate() {
                // SAFETY: AVX is enabled here (the caller checked the machine)
                unsafe { tension4(lanes, 4 * q, springs, s + 4 * q, quad) };
            }
            lanes.tension(done, springs, s + done, rest);
        });
    }

    /// The forces of springs `s..s + 4`, gathered in lanes `l..l + 4`, into `out`
    /// (4 entries), as [`Lanes::tension`].
    #[target_feature(enable = "avx")]
    #[inline]
    #[allow(unused_unsafe)] // (the arithmetic intrinsics are safe here from Rust 1.87 on)
    unsafe fn tension4(lanes: &Lanes, l: usize, springs: &SpringArrays, s: usize, out: &mut [[f64; 4]]) {
        let load = |a: &[f64]| {
            let a = &a[..4]; // (bounds checked here: the load below reads these 4)
                             // SAFETY: 4 f64 in a slice; AVX is enabled.
            unsafe { _mm256_loadu_pd(a.as_ptr()) }
        };
        let at = |a: &[f64; super::LANES]| load(&a[l..]);
        let (dx, dy, dz) = (at(&lanes.d[0]), at(&lanes.d[1]), at(&lanes.d[2]));
        let (ux, uy, uz) = (at(&lanes.u[0]), at(&lanes.u[1]), at(&lanes.u[2]));
        let k = load(&springs.k[s..]);
        let rest = load(&springs.rest_length[s..]);
        let c = load(&springs.damping[s..]);
        // SAFETY: arithmetic on registers; AVX is enabled.
        let rows = unsafe {
            let square = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
                _mm256_mul_pd(dz, dz),
            );
            let len = _mm256_sqrt_pd(square);
            let (nx, ny, nz) = (_mm256_div_pd(dx, len), _mm256_div_pd(dy, len), _mm256_div_pd(dz, len));
            let along = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(ux, nx), _mm256_mul_pd(uy, ny)),
                _mm256_mul_pd(uz, nz),
            );
            let tension = _mm256_add_pd(_mm256_mul_pd(k, _mm256_sub_pd(len, rest)), _mm256_mul_pd(c, along));
            // all ones where L > 0 (false for NaN, as the scalar comparison), zeros elsewhere
            let live = _mm256_cmp_pd::<_CMP_GT_OQ>(len, _mm256_setzero_pd());
            let fx = _mm256_and_pd(live, _mm256_mul_pd(tension, nx));
            let fy = _mm256_and_pd(live, _mm256_mul_pd(tension, ny));
            let fz = _mm256_and_pd(live, _mm256_mul_pd(tension, nz));
            let one = _mm256_and_pd(live, _mm256_set1_pd(1.0));
            // transposed: the rows (fx, fy, fz, one) into one [fx, fy, fz, 1] per spring
            let (a, b) = (_mm256_unpacklo_pd(fx, fy), _mm256_unpackhi_pd(fx, fy)); // lanes 0, 2 | 1, 3
            let (e, f) = (_mm256_unpacklo_pd(fz, one), _mm256_unpackhi_pd(fz, one));
            [
                _mm256_permute2f128_pd::<0x20>(a, e),
                _mm256_permute2f128_pd::<0x20>(b, f),
                _mm256_permute2f128_pd::<0x31>(a, e),
                _mm256_permute2f128_pd::<0x31>(b, f),
            ]
        };
        for (o, row) in out[..4].iter_mut().zip(rows) {
            // SAFETY: one [f64; 4] of `out`; AVX is enabled.
            unsafe { _mm256_storeu_pd(o.as_mut_ptr(), row) };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::testing::Rng;

    /// The pass against the one loop it stands for, bit for bit: each spring's force by the
    /// formula of the module doc, added to end i and subtracted from end j in spring order.
    /// A random network of 1003 springs (blocks of 64 and of 4 and the few left over, on the
    /// machine's vector path and the scalar one), with coincident ends (no force), rest
    /// length 0, and a particle at NaN (its springs add nothing either).
    #[test]
    fn the_pass_is_the_plain_loop_to_the_bit() {
        let mut rng = Rng::new(7);
        let n = 300;
        let mut x = rng.vec(3 * n, -1.0, 1.0);
        let v = rng.vec(3 * n, -1.0, 1.0);
        x.copy_within(0..3, 3); // particles 0 and 1 coincide
        x[3 * 7 + 1] = f64::NAN;
        let count = 1003;
        let (mut i, mut j) = (vec![0, 2], vec![1, 7]);
        while i.len() < count {
            let (a, b) = (rng.index(n), rng.index(n));
            if a != b {
                i.push(a);
                j.push(b);
            }
        }
        let k = rng.vec(count, 10.0, 100.0);
        let rest: Vec<f64> = (0..count)
            .map(|s| if s % 5 == 0 { 0.0 } else { rng.uniform(0.2, 1.6) })
            .collect();
        let c = rng.vec(count, 0.0, 3.0);
        let springs = SpringArrays {
            i: &i,
            j: &j,
            k: &k,
            rest_length: &rest,
            damping: &c,
        };
        let base = rng.vec(3 * n, -5.0, 5.0); // (the other forces' sum the springs add to)
        let mut expected = base.clone();
        for s in 0..count {
            let (a, b) = (3 * i[s], 3 * j[s]);
            let d = [x[b] - x[a], x[b + 1] - x[a + 1], x[b + 2] - x[a + 2]];
            let u = [v[b] - v[a], v[b + 1] - v[a + 1], v[b + 2] - v[a + 2]];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if len > 0.0 {
                let nv = [d[0] / len, d[1] / len, d[2] / len];
                let tension = k[s] * (len - rest[s]) + c[s] * crate::vec3::dot(u, nv);
                for q in 0..3 {
                    expected[a + q] += tension * nv[q];
                    expected[b + q] -= tension * nv[q];
                }
            }
        }
        let mut got = base.clone();
        Scratch::default().accumulate(&springs, &x, &v, &mut got);
        let mut scalar = vec![[0.0; 4]; count];
        tension_lanes(&springs, 0, &x, &v, &mut scalar, |lanes, springs, s, block| {
            lanes.tension(0, springs, s, block)
        });
        let mut vector = vec![[0.0; 4]; count];
        tension_chunk(&springs, 0, &x, &v, &mut vector);
        for (p, (g, e)) in got.iter().zip(&expected).enumerate() {
            assert_eq!(
                g.to_bits(),
                e.to_bits(),
                "particle {}, coordinate {}: {g} vs {e}",
                p / 3,
                p % 3
            );
        }
        for s in 0..count {
            let same = scalar[s].iter().zip(&vector[s]).all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "spring {s}: {:?} (scalar) vs {:?}", scalar[s], vector[s]);
        }
        assert_eq!(vector[0], [0.0; 4], "coincident ends: no force");
        assert_eq!(vector[1], [0.0; 4], "an end at NaN: no force");
    }
}
