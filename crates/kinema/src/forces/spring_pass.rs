//! The springs' force pass: each spring's force on its first end (springs in lanes, so that
//! the square roots and divisions of several springs go in one vector instruction), then each
//! particle's sum over the springs it ends, in spring order.
//!
//! Both passes run on all threads in chunks of a fixed size, and each particle's sum is the
//! same additions in the same order as one loop over the springs that adds F_i to end i and
//! subtracts it from end j: the result is the same for any number of threads, and the same
//! bits as that loop.
//!
//! The tension pass takes the springs placed by their lower end (a stable counting sort, once
//! for a set of springs), not in the order they were given: the forces a particle sums were
//! then mostly computed next to each other, by the same thread, from positions that thread
//! drifted. A cloth's springs given family by family (all the structural ones, then the shear
//! ones, …) had each particle sum forces from six places of the tension buffer, half of them
//! written by the other core: the 100 × 100 cloth of `benchmarks/springs.py` ran 20 % more
//! steps a second on 2 threads with its springs given in this order than in its own (the same
//! on 1 thread). The sums keep each particle's springs in their given order: the same bits.

use rayon::prelude::*;

/// Springs per chunk of the tension pass (fixed, so the work is split the same way for any
/// number of threads).
const CHUNK: usize = 1024;

/// Particles per chunk of the sum pass: each particle's sum is its own (the same bits for any
/// chunks), and a cloth of 10⁴ nodes in chunks of 4096 left one of two threads idle a third
/// of the pass.
const SUM_CHUNK: usize = 1024;

/// What the pass reads of the springs: ends, stiffness (N/m), rest length (m) and dashpot
/// coefficient (N·s/m), one per spring.
pub(super) struct SpringArrays<'a> {
    pub i: &'a [usize],
    pub j: &'a [usize],
    pub k: &'a [f64],
    pub rest_length: &'a [f64],
    pub damping: &'a [f64],
}

/// The springs as the tension pass takes them: by their lower end min(i, j), in their given
/// order among those of one lower end (a copy, 40 B a spring).
#[derive(Debug, Clone, Default)]
struct Placed {
    i: Vec<usize>,
    j: Vec<usize>,
    k: Vec<f64>,
    rest_length: Vec<f64>,
    damping: Vec<f64>,
}

impl Placed {
    fn arrays(&self) -> SpringArrays<'_> {
        SpringArrays {
            i: &self.i,
            j: &self.j,
            k: &self.k,
            rest_length: &self.rest_length,
            damping: &self.damping,
        }
    }
}

/// The force pass's buffers: each placed spring's force on its end i, N, with a fourth entry
/// 1 (0 for a spring of zero length, which has no direction and adds nothing); the springs
/// placed ([`Placed`]); and for each particle the springs it ends, in their given order
/// (`place << 1 | 1` where it is the end j), compressed by particle (`start`, `ends`).
#[derive(Debug, Clone, Default)]
pub(super) struct Scratch {
    tension: Vec<[f64; 4]>,
    placed: Placed,
    start: Vec<u32>,
    ends: Vec<u32>,
}

impl PartialEq for Scratch {
    fn eq(&self, _: &Self) -> bool {
        true // buffers, not data
    }
}

impl Scratch {
    /// The sum pass's chunk of particles ([`SUM_CHUNK`]).
    pub(super) const SUM_CHUNK: usize = SUM_CHUNK;

    /// Adds F_i = [k (L − L₀) + c (u·n)] n to each spring's first end and −F_i to its second
    /// in `f` (N, 3 per particle; `x`, `v` in m and m/s, 3 per particle, every index of
    /// `springs` below their particle count); then, with `each`, calls it on each chunk of
    /// [`SUM_CHUNK`] particles of `f` as soon as that chunk's sums are done
    /// ([`super::Force::accumulate_then`]). The springs are placed the first time and kept:
    /// a scratch serves one set of springs (the springs drop it when they change).
    pub(super) fn accumulate(
        &mut self,
        springs: &SpringArrays,
        x: &[f64],
        v: &[f64],
        f: &mut [f64],
        each: Option<&super::ChunkWork>,
    ) {
        let n = x.len() / 3;
        if self.start.len() != n + 1 || self.placed.i.len() != springs.i.len() {
            self.place(springs, n);
        }
        let Scratch {
            tension,
            placed,
            start,
            ends,
        } = self;
        let placed = placed.arrays();
        tension.resize(placed.i.len(), [0.0; 4]);
        tension.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
            tension_chunk(&placed, c * CHUNK, x, v, out);
        });
        f.par_chunks_mut(3 * SUM_CHUNK).enumerate().for_each(|(c, fc)| {
            let ends = Ends {
                tension,
                start,
                ends,
                first: c * SUM_CHUNK,
            };
            sum_chunk(&ends, fc);
            if let Some(each) = each {
                each(c, fc);
            }
        });
    }

    /// Places the springs by their lower end (a counting sort, stable: [`Placed`]), and
    /// lists for each of `n` particles the springs it ends, in their given order, by their
    /// places: `start` and `ends`.
    fn place(&mut self, springs: &SpringArrays, n: usize) {
        let count = springs.i.len();
        let low = |s: usize| springs.i[s].min(springs.j[s]);
        // the first place of each lower end, then each spring's place
        let mut next = vec![0u32; n + 1];
        for s in 0..count {
            next[low(s) + 1] += 1;
        }
        for p in 1..=n {
            next[p] += next[p - 1];
        }
        let mut at = vec![0u32; count];
        for (s, at) in at.iter_mut().enumerate() {
            let p = low(s);
            *at = next[p];
            next[p] += 1;
        }
        let placed = &mut self.placed;
        placed.i.resize(count, 0);
        placed.j.resize(count, 0);
        placed.k.resize(count, 0.0);
        placed.rest_length.resize(count, 0.0);
        placed.damping.resize(count, 0.0);
        for (s, &q) in at.iter().enumerate() {
            let q = q as usize;
            placed.i[q] = springs.i[s];
            placed.j[q] = springs.j[s];
            placed.k[q] = springs.k[s];
            placed.rest_length[q] = springs.rest_length[s];
            placed.damping[q] = springs.damping[s];
        }
        let (start, ends) = (&mut self.start, &mut self.ends);
        start.clear();
        start.resize(n + 1, 0);
        for p in springs.i.iter().chain(springs.j) {
            start[p + 1] += 1;
        }
        for p in 1..=n {
            start[p] += start[p - 1];
        }
        next.clear();
        next.extend_from_slice(&start[..n]);
        ends.clear();
        ends.resize(2 * count, 0);
        for (s, &q) in at.iter().enumerate() {
            for (end, p) in [(0, springs.i[s]), (1, springs.j[s])] {
                ends[next[p] as usize] = q << 1 | end;
                next[p] += 1;
            }
        }
    }
}

/// The sums of one chunk of particles into `fc` (3 values a particle): [`avx::sum_chunk`]
/// where the machine has AVX (chosen at run time), the plain loop elsewhere; the same bits.
fn sum_chunk(ends: &Ends, fc: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the machine has AVX (checked just above).
        unsafe { avx::sum_chunk(ends, fc) };
        return;
    }
    for (l, fp) in fc.chunks_exact_mut(3).enumerate() {
        let mut sum = [fp[0], fp[1], fp[2]];
        for (g, flip) in ends.of(l) {
            for q in 0..3 {
                sum[q] += f64::from_bits(g[q].to_bits() ^ flip);
            }
        }
        fp.copy_from_slice(&sum);
    }
}

/// The per-particle sums of one chunk of particles (from particle `first` on): the springs
/// each ends, with their forces on end i (`tension`).
struct Ends<'a> {
    tension: &'a [[f64; 4]],
    start: &'a [u32],
    ends: &'a [u32],
    first: usize,
}

impl Ends<'_> {
    /// The end entries of particle `first + l`: for each spring it ends, in their given order,
    /// `place << 1 | 1` where it is the end j (else `place << 1`).
    #[inline(always)]
    fn list(&self, l: usize) -> &[u32] {
        let p = self.first + l;
        &self.ends[self.start[p] as usize..self.start[p + 1] as usize]
    }

    /// The forces of the springs that particle `first + l` ends, in their given order, each with
    /// the sign bit to flip (where the particle is the end j: sum − g computed as
    /// sum + (−g), the same number, since IEEE 754 defines the difference so, signed zeros
    /// included). A spring with coincident ends is left out (no force).
    #[inline(always)]
    fn of(&self, l: usize) -> impl Iterator<Item = (&[f64; 4], u64)> + '_ {
        self.list(l)
            .iter()
            .map(|&e| (&self.tension[(e >> 1) as usize], u64::from(e & 1) << 63))
            .filter(|(g, _)| g[3] != 0.0)
    }
}

/// The tension pass over the springs `first..first + out.len()`: [`avx::tension_chunk`]
/// where the machine has AVX (chosen at run time), [`tension`] spring by spring elsewhere;
/// the same bits either way.
fn tension_chunk(springs: &SpringArrays, first: usize, x: &[f64], v: &[f64], out: &mut [[f64; 4]]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the machine has AVX (checked just above).
        unsafe { avx::tension_chunk(springs, first, x, v, out) };
        return;
    }
    for (o, s) in out.iter_mut().zip(first..) {
        *o = tension(springs, s, x, v);
    }
}

/// The force on end i of spring `s`, with a fourth entry 1 (all 0 for coincident ends).
/// With d = x_j − x_i, L = |d| = √((d_x² + d_y²) + d_z²), n = d / L and u = v_j − v_i:
/// F_i = [k (L − L₀) + c ((u_x n_x + u_y n_y) + u_z n_z)] n, in exactly these operations
/// (the order of `vec3::dot`); [`avx::tension4`] does the same ones four springs at a time.
#[inline(always)]
fn tension(springs: &SpringArrays, s: usize, x: &[f64], v: &[f64]) -> [f64; 4] {
    let (a, b) = (3 * springs.i[s], 3 * springs.j[s]);
    let (xa, xb, va, vb) = (&x[a..a + 3], &x[b..b + 3], &v[a..a + 3], &v[b..b + 3]);
    let d = [xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]];
    let u = [vb[0] - va[0], vb[1] - va[1], vb[2] - va[2]];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if len > 0.0 {
        let n = [d[0] / len, d[1] / len, d[2] / len];
        let along = u[0] * n[0] + u[1] * n[1] + u[2] * n[2];
        let t = springs.k[s] * (len - springs.rest_length[s]) + springs.damping[s] * along;
        [t * n[0], t * n[1], t * n[2], 1.0]
    } else {
        [0.0; 4] // (NaN too)
    }
}

/// The two passes with AVX: four springs' forces at once, and each particle's sum in one
/// register. The same IEEE operations in the same order, lane by lane, as [`tension`] and
/// the plain sum (vector square roots and divisions are correctly rounded like scalar ones,
/// and no multiply-add is fused): the same bits.
#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{tension, Ends, SpringArrays};
    use std::arch::x86_64::*;

    /// [`super::tension_chunk`] with AVX: four springs at a time by [`gather4`] and
    /// [`tension4`]; a group with an end at the last particle, and the few springs left at
    /// the chunk's end, one by one.
    ///
    /// A chunk none of whose springs ends at the last particle (all but one or two chunks of
    /// a cloth) is checked once and then loaded without a check per load, two groups at a
    /// time ([`gather4_within`]; their two chains of square root, division and products side
    /// by side): 4 % more steps a second on one thread for the 100 × 100 cloth of
    /// `benchmarks/springs.py` than group by group with the loads checked.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn tension_chunk(springs: &SpringArrays, first: usize, x: &[f64], v: &[f64], out: &mut [[f64; 4]]) {
        let whole = out.len() / 4 * 4;
        let span = first..first + whole;
        let (ci, cj) = (&springs.i[span.clone()], &springs.j[span]);
        // each load of a group reads 4 values from 3p, the last at 3p + 3 < 3n: p + 1 < n
        let n = x.len().min(v.len()) / 3;
        let below_last = |ends: &[usize]| ends.iter().fold(true, |all, &p| all & (p + 1 < n));
        if below_last(ci) && below_last(cj) {
            let mut octs = out[..whole].chunks_exact_mut(8);
            for (o, oct) in (&mut octs).enumerate() {
                let s = first + 8 * o;
                let (lo, hi) = oct.split_at_mut(4);
                let (a, b) = (&ci[8 * o..8 * o + 8], &cj[8 * o..8 * o + 8]);
                // SAFETY: every end of the chunk's groups is below n − 1 (checked above); AVX
                // is enabled (the caller checked the machine).
                unsafe {
                    let (d0, u0) = gather4_within(&a[..4], &b[..4], x, v);
                    let (d1, u1) = gather4_within(&a[4..], &b[4..], x, v);
                    tension4(d0, u0, springs, s, lo);
                    tension4(d1, u1, springs, s + 4, hi);
                }
            }
            let done = whole / 8 * 8;
            if done < whole {
                let (a, b) = (&ci[done..whole], &cj[done..whole]);
                // SAFETY: as above.
                unsafe {
                    let (d, u) = gather4_within(a, b, x, v);
                    tension4(d, u, springs, first + done, &mut out[done..whole]);
                }
            }
        } else {
            for (q, quad) in out[..whole].chunks_exact_mut(4).enumerate() {
                let s = first + 4 * q;
                // SAFETY (both): AVX is enabled here (the caller checked the machine).
                match unsafe { gather4(springs, s, x, v) } {
                    Some((d, u)) => unsafe { tension4(d, u, springs, s, quad) },
                    None => {
                        for (o, s) in quad.iter_mut().zip(s..) {
                            *o = tension(springs, s, x, v);
                        }
                    }
                }
            }
        }
        for (o, s) in out[whole..].iter_mut().zip(first + whole..) {
            *o = tension(springs, s, x, v);
        }
    }

    /// [`gather4`] of the four springs with ends `a` and `b` (4 each), every one of them
    /// below the last particle, without checks.
    ///
    /// # Safety
    /// AVX is enabled, and every end p of `a` and `b` has 3p + 4 <= `x.len()`, `v.len()`.
    #[target_feature(enable = "avx")]
    #[inline]
    #[allow(unused_unsafe)]
    unsafe fn gather4_within(a: &[usize], b: &[usize], x: &[f64], v: &[f64]) -> ([__m256d; 3], [__m256d; 3]) {
        let (mut d, mut u) = ([_mm256_setzero_pd(); 4], [_mm256_setzero_pd(); 4]);
        let (x, v) = (x.as_ptr(), v.as_ptr());
        for l in 0..4 {
            let (a, b) = (3 * a[l], 3 * b[l]);
            // SAFETY (all): 4 values from 3p, within the arrays (the caller's promise).
            unsafe {
                let (xa, xb) = (_mm256_loadu_pd(x.add(a)), _mm256_loadu_pd(x.add(b)));
                let (va, vb) = (_mm256_loadu_pd(v.add(a)), _mm256_loadu_pd(v.add(b)));
                (d[l], u[l]) = (_mm256_sub_pd(xb, xa), _mm256_sub_pd(vb, va));
            }
        }
        // SAFETY: AVX is enabled.
        unsafe { (columns(d), columns(u)) }
    }

    /// One 4-wide load: the coordinates of particle `a` and the next one's first (ignored),
    /// `None` for the last particle (its load would pass the end).
    #[target_feature(enable = "avx")]
    #[inline]
    unsafe fn load_at(a: &[f64], p: usize) -> Option<__m256d> {
        let a = a.get(3 * p..3 * p + 4)?;
        // SAFETY: 4 f64 in a slice; AVX is enabled.
        Some(unsafe { _mm256_loadu_pd(a.as_ptr()) })
    }

    /// d = x_j − x_i and u = v_j − v_i of springs `s..s + 4`, as rows (x, y, z) of four
    /// lanes (one spring a lane); `None` where an end is the last particle.
    #[target_feature(enable = "avx")]
    #[inline]
    #[allow(unused_unsafe)] // (the arithmetic intrinsics are safe here from Rust 1.87 on)
    unsafe fn gather4(springs: &SpringArrays, s: usize, x: &[f64], v: &[f64]) -> Option<([__m256d; 3], [__m256d; 3])> {
        let (mut d, mut u) = ([_mm256_setzero_pd(); 4], [_mm256_setzero_pd(); 4]);
        for l in 0..4 {
            let (a, b) = (springs.i[s + l], springs.j[s + l]);
            // SAFETY (all): AVX is enabled.
            let (xa, xb) = unsafe { (load_at(x, a)?, load_at(x, b)?) };
            let (va, vb) = unsafe { (load_at(v, a)?, load_at(v, b)?) };
            (d[l], u[l]) = unsafe { (_mm256_sub_pd(xb, xa), _mm256_sub_pd(vb, va)) };
        }
        // SAFETY: AVX is enabled.
        unsafe { Some((columns(d), columns(u))) }
    }

    /// The first three columns of the 4 × 4 matrix with rows `r`: the x, y and z of the
    /// four springs.
    #[target_feature(enable = "avx")]
    #[inline]
    #[allow(unused_unsafe)]
    unsafe fn columns(r: [__m256d; 4]) -> [__m256d; 3] {
        // SAFETY: AVX is enabled.
        unsafe {
            let (t0, t1) = (_mm256_unpacklo_pd(r[0], r[1]), _mm256_unpackhi_pd(r[0], r[1])); // x0 x1 z0 z1 | y0 y1 . .
            let (t2, t3) = (_mm256_unpacklo_pd(r[2], r[3]), _mm256_unpackhi_pd(r[2], r[3])); // x2 x3 z2 z3 | y2 y3 . .
            [
                _mm256_permute2f128_pd::<0x20>(t0, t2),
                _mm256_permute2f128_pd::<0x20>(t1, t3),
                _mm256_permute2f128_pd::<0x31>(t0, t2),
            ]
        }
    }

    /// The forces of springs `s..s + 4` from their d and u (rows of four lanes) into `out`
    /// (4 entries), as [`tension`].
    #[target_feature(enable = "avx")]
    #[inline]
    #[allow(unused_unsafe)]
    unsafe fn tension4(d: [__m256d; 3], u: [__m256d; 3], springs: &SpringArrays, s: usize, out: &mut [[f64; 4]]) {
        let load = |a: &[f64]| {
            let a = &a[s..s + 4]; // (bounds checked here: the load below reads these 4)
                                  // SAFETY: 4 f64 in a slice; AVX is enabled.
            unsafe { _mm256_loadu_pd(a.as_ptr()) }
        };
        let (k, rest, c) = (load(springs.k), load(springs.rest_length), load(springs.damping));
        let ([dx, dy, dz], [ux, uy, uz]) = (d, u);
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

    /// The per-particle sums of one chunk of particles with AVX: x, y and z of the sum in
    /// the first three lanes of one register (the fourth adds the flags, and is dropped),
    /// each spring's force added with its sign bit flipped by one xor.
    ///
    /// The sign masks are two registers picked by the entry's end bit (not one made from it
    /// at each entry: four instructions of the loop's 19), and a spring of coincident ends is
    /// known by its flag's bits (exactly 1.0 or +0.0): 8 % less time in the sum pass of the
    /// 100 × 100 cloth on one thread (2–3 % more steps a second). Two particles' sums side by
    /// side (two chains of additions) gained 1 % more: not kept.
    #[target_feature(enable = "avx")]
    #[allow(unused_unsafe)]
    pub(super) unsafe fn sum_chunk(ends: &Ends, fc: &mut [f64]) {
        // SAFETY: AVX is enabled.
        let flips = unsafe { [_mm256_setzero_pd(), _mm256_set1_pd(-0.0)] };
        for (l, fp) in fc.chunks_exact_mut(3).enumerate() {
            // SAFETY (all): AVX is enabled; every load reads one [f64; 4].
            unsafe {
                let mut sum = _mm256_set_pd(0.0, fp[2], fp[1], fp[0]);
                for &e in ends.list(l) {
                    let g = &ends.tension[(e >> 1) as usize];
                    if g[3].to_bits() != 0 {
                        let g = _mm256_loadu_pd(g.as_ptr());
                        sum = _mm256_add_pd(sum, _mm256_xor_pd(g, flips[(e & 1) as usize]));
                    }
                }
                let mut out = [0.0; 4];
                _mm256_storeu_pd(out.as_mut_ptr(), sum);
                fp.copy_from_slice(&out[..3]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::testing::Rng;

    /// The pass's view of springs given as arrays: ends, stiffness, rest length, damping.
    fn arrays<'a>(i: &'a [usize], j: &'a [usize], k: &'a [f64], rest: &'a [f64], c: &'a [f64]) -> SpringArrays<'a> {
        SpringArrays {
            i,
            j,
            k,
            rest_length: rest,
            damping: c,
        }
    }

    /// The pass against the one loop it stands for, bit for bit: each spring's force by the
    /// formula of the module doc, added to end i and subtracted from end j in spring order.
    /// A random network of 1003 springs (groups of four and the few left over, on the
    /// machine's vector path and the scalar one), with coincident ends (no force), rest
    /// length 0, a particle at NaN (its springs add nothing either) and springs ending at the
    /// last particle (the vector path's loads stop short of it); and the springs after those,
    /// none of which ends at the last particle (the vector path's unchecked loads).
    #[test]
    fn the_pass_is_the_plain_loop_to_the_bit() {
        let mut rng = Rng::new(7);
        let n = 300;
        let mut x = rng.vec(3 * n, -1.0, 1.0);
        let v = rng.vec(3 * n, -1.0, 1.0);
        x.copy_within(0..3, 3); // particles 0 and 1 coincide
        x[3 * 7 + 1] = f64::NAN;
        let count = 1003;
        let (mut i, mut j) = (vec![0, 2, n - 1, 5, 9], vec![1, 7, 3, n - 1, 4]);
        while i.len() < count {
            let (a, b) = (rng.index(n - 1), rng.index(n - 1)); // (only the first 5 end at n − 1)
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
        let springs = arrays(&i, &j, &k, &rest, &c);
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
        Scratch::default().accumulate(&springs, &x, &v, &mut got, None);
        let scalar: Vec<[f64; 4]> = (0..count).map(|s| tension(&springs, s, &x, &v)).collect();
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
        let mut within = vec![[0.0; 4]; count - 5];
        tension_chunk(&springs, 5, &x, &v, &mut within);
        for s in 0..count {
            let same = scalar[s].iter().zip(&vector[s]).all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "spring {s}: {:?} (scalar) vs {:?}", scalar[s], vector[s]);
            if s >= 5 {
                let same = scalar[s].iter().zip(&within[s - 5]).all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(
                    same,
                    "spring {s}, none at the last particle: {:?} (scalar) vs {:?}",
                    scalar[s],
                    within[s - 5]
                );
            }
        }
        assert_eq!(vector[0], [0.0; 4], "coincident ends: no force");
        assert_eq!(vector[1], [0.0; 4], "an end at NaN: no force");
    }

    /// The placement: the springs by their lower end, in their given order among those of
    /// one lower end (so that a cloth's particle finds the forces it sums next to each
    /// other), and each particle's list names the same springs as the given order, in that
    /// order, at their places. Springs given from the highest particle down, so that the
    /// given order is not already the placed one.
    #[test]
    fn springs_are_placed_by_their_lower_end_and_each_particle_lists_its_own_in_their_given_order() {
        let mut rng = Rng::new(11);
        let n = 50;
        let (mut i, mut j) = (Vec::new(), Vec::new());
        for s in 0..400 {
            let a = n - 1 - s % n;
            let b = (a + 1 + rng.index(n - 1)) % n;
            i.push(a);
            j.push(b);
        }
        let count = i.len();
        let (k, rest, c) = (rng.vec(count, 1.0, 2.0), rng.vec(count, 0.1, 0.2), rng.vec(count, 0.0, 1.0));
        let springs = arrays(&i, &j, &k, &rest, &c);
        let mut scratch = Scratch::default();
        scratch.place(&springs, n);
        let placed = &scratch.placed;
        // the given spring at each place: by its values, which are all distinct
        let given: Vec<usize> = (0..count)
            .map(|q| (0..count).find(|&s| k[s] == placed.k[q]).unwrap())
            .collect();
        for q in 0..count {
            let s = given[q];
            assert_eq!((placed.i[q], placed.j[q]), (i[s], j[s]), "place {q}");
            assert_eq!((placed.rest_length[q], placed.damping[q]), (rest[s], c[s]), "place {q}");
            if q > 0 {
                let (low, before) = (i[s].min(j[s]), i[given[q - 1]].min(j[given[q - 1]]));
                assert!(
                    before < low || (before == low && given[q - 1] < s),
                    "place {q}: spring {s} (lower end {low}) after spring {} (lower end {before})",
                    given[q - 1]
                );
            }
        }
        for p in 0..n {
            let listed: Vec<(usize, u32)> = scratch.ends[scratch.start[p] as usize..scratch.start[p + 1] as usize]
                .iter()
                .map(|&e| (given[(e >> 1) as usize], e & 1))
                .collect();
            let expected: Vec<(usize, u32)> = (0..count)
                .filter_map(|s| {
                    if i[s] == p {
                        Some((s, 0))
                    } else if j[s] == p {
                        Some((s, 1))
                    } else {
                        None
                    }
                })
                .collect();
            assert_eq!(listed, expected, "particle {p}");
        }
    }
}
