//! Small vector helpers, the one set the crate uses: 3-vectors, and flat arrays (3 values per particle).

/// The 3 coordinates of particle `i` in a flat array (`a[3i..3i+3]`).
#[inline]
pub(crate) fn get(a: &[f64], i: usize) -> [f64; 3] {
    [a[3 * i], a[3 * i + 1], a[3 * i + 2]]
}

/// Adds `s · d` to particle `i`'s 3 entries of the flat array `a`.
#[inline]
pub(crate) fn add_scaled(a: &mut [f64], i: usize, s: f64, d: [f64; 3]) {
    for k in 0..3 {
        a[3 * i + k] += s * d[k];
    }
}

/// The parabola of a constant acceleration, x + v t + ½ a t² (m; x in m, v in m/s, a in
/// m/s², t in s): a particle's path within a step, or a pair's separation with the relative
/// v and a. The one place it is written (summed in this order: the same bits everywhere).
#[inline]
pub(crate) fn parabola(x: [f64; 3], v: [f64; 3], a: [f64; 3], t: f64) -> [f64; 3] {
    [0, 1, 2].map(|k| x[k] + v[k] * t + 0.5 * a[k] * t * t)
}

#[inline]
pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn scale(s: f64, a: [f64; 3]) -> [f64; 3] {
    [s * a[0], s * a[1], s * a[2]]
}

#[inline]
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// a·b of two flat arrays of the same length (the unscaled sum, in index order).
#[inline]
pub(crate) fn dot_slices(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Index and value of the first non-finite entry of `a`, for error messages. First whether
/// there is one at all, by [`non_finite_bits`] or-ed over `a` (a loop without a branch, which
/// the compiler makes vector operations of), then where, only if there is.
pub(crate) fn first_non_finite(a: &[f64]) -> Option<(usize, f64)> {
    if a.iter().fold(0, |bits, &c| bits | non_finite_bits(c)) == 0 {
        return None;
    }
    a.iter().position(|c| !c.is_finite()).map(|p| (p, a[p]))
}

/// 0 for a finite `c`, not 0 for ±∞ and NaN: the bits of c − c (+0 for a finite c, NaN
/// else). Or-ed over many values, a test for a non-finite one without a branch a value.
#[inline(always)]
pub(crate) fn non_finite_bits(c: f64) -> u64 {
    #[allow(clippy::eq_op)] // (c − c on purpose)
    let d = c - c;
    d.to_bits()
}
