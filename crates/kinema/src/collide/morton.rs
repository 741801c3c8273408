//! Morton order: positions sorted along a Z-order curve of cells, so that particles near in
//! space are mostly near in memory (LAMMPS's `atom_modify sort`, HOOMD-blue's SFCPackTuner).
//! The world sorts by it for the contact force (`world/order.rs`), the event-driven
//! path for its own arrays (`event_driven/`).

use rayon::prelude::*;

/// Bits of each cell coordinate in a Morton code (3 × 21 = 63).
const MORTON_BITS: u32 = 21;

/// `v`'s low 21 bits spread to every third bit (bit k to bit 3k).
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// The Morton code of cell (i, j, k): their bits interleaved, x lowest.
pub(crate) fn morton(c: [u64; 3]) -> u64 {
    spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2
}

/// The order that sorts positions `x` (m, 3 per particle) by the Morton code of their cells
/// of width `width` (m) from `origin`, ties in index order: `old_of_new[i]` is the index now
/// of the particle that goes to place i.
///
/// Each key is one u64, the code above the index (8 B per particle while sorting, not 16):
/// the index takes ⌈log₂ N⌉ bits and each cell coordinate B = ⌊(64 − those) / 3⌋ ≥ 10 of the
/// rest; where the particles span more than 2^B cells the cells are widened to fit.
pub(crate) fn morton_order(x: &[f64], origin: [f64; 3], width: f64) -> Vec<u32> {
    morton_order_in(x, origin, width, &mut vec![0; x.len() / 3])
}

/// [`morton_order`] with its keys in `keys`' room (at least one a particle; its values are
/// not to be read after): a caller with a buffer it writes before it reads next lends it, and
/// the sort makes only the order (4 B a particle, not 12).
pub(crate) fn morton_order_in(x: &[f64], origin: [f64; 3], width: f64, keys: &mut [u64]) -> Vec<u32> {
    let n = x.len() / 3;
    let keys = &mut keys[..n];
    let index_bits = usize::BITS - n.saturating_sub(1).leading_zeros();
    let bits = ((64 - index_bits) / 3).min(MORTON_BITS);
    let top = ((1u64 << bits) - 1) as f64;
    let span = x
        .par_chunks_exact(3)
        .map(|p| (0..3).map(|k| p[k] - origin[k]).fold(0.0, f64::max))
        .reduce(|| 0.0, f64::max);
    let width = width.max(span / top);
    keys.par_iter_mut()
        .zip(x.par_chunks_exact(3))
        .enumerate()
        .for_each(|(i, (key, p))| {
            // `as u64` truncates (the floor for t ≥ 0, without `f64::floor`'s library call)
            // and saturates: below the origin is cell 0, NaN is 0, beyond the top the top.
            let cell = [0, 1, 2].map(|k| ((p[k] - origin[k]) / width).min(top) as u64);
            *key = morton(cell) << index_bits | i as u64;
        });
    keys.par_sort_unstable(); // the keys are distinct: one result for any thread count
    let mask = (1u64 << index_bits) - 1;
    keys.par_iter().map(|k| (k & mask) as u32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_codes_interleave_the_bits() {
        assert_eq!(morton([1, 0, 0]), 0b001);
        assert_eq!(morton([0, 1, 0]), 0b010);
        assert_eq!(morton([0, 0, 1]), 0b100);
        assert_eq!(morton([3, 5, 6]), 0b110_101_011);
        let top = (1 << MORTON_BITS) - 1;
        assert_eq!(morton([top, top, top]), (1 << 63) - 1);
    }

    #[test]
    fn the_order_visits_cells_along_the_curve_and_keeps_ties() {
        // Cells (1,1,0), (0,0,0), (1,0,0), (0,0,0) again: codes 3, 0, 1, 0.
        let x = [1.5, 1.5, 0.5, 0.2, 0.2, 0.2, 1.2, 0.9, 0.1, 0.7, 0.7, 0.7];
        assert_eq!(morton_order(&x, [0.0; 3], 1.0), vec![1, 3, 2, 0]);
        // below the origin: cell 0
        assert_eq!(morton_order(&[-5.0, 0.0, 0.0, 0.5, 0.5, 0.5], [0.0; 3], 1.0), vec![0, 1]);
    }
}
