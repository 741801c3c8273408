//! The first look of the pair pass (`pairs.rs`) for laws whose pairs act only while they
//! overlap (every law but JKR's, which holds a pair past touching) and carry no memory (no
//! tangential part): which of a chunk's listed pairs overlap, and which of its particles the
//! pass must visit at all.
//!
//! Most particles of a gas touch nothing: a list holds every pair within r_i + r_j + skin,
//! and in the granular gas of `benchmarks/granular_gas.py` (density 0.3, skin 0.3 d) a
//! particle has about one listed partner and 0.06–0.08 overlapping ones (measured at steps
//! 300–1000 of N = 103,823). The pass's loop paid for its whole body at every particle (its
//! locals spilled around the test, five prefetches an entry for a contact's reads, the
//! check of the position); here the test and the check run in a loop of their own, which
//! holds nothing but the particle's position and radius, and the pass then visits the
//! particles with an overlapping pair or a collider candidate alone, in the same order.
//!
//! The test is [`ContactForce::overlaps`]'s, the same expression on the same numbers: the
//! pairs found are those the pass found, in the same order, and the forces the same bits.

use super::ContactForce;
use crate::collide::neighbour_list::Rows;
use crate::simd::prefetch;
use crate::vec3::first_non_finite;

/// How many list entries ahead of its reads the scan asks for the partners' positions and
/// radii ([`prefetch`]): a dozen particles' rows at the pass's 16 covered the 10⁵ gas (its
/// positions in the last-level cache) but not the 10⁶ one, whose reads go to memory at
/// about 3 ns an entry; 48: the 10⁶ gas 4 % faster, the 10⁵ one the same.
const AHEAD: usize = 48;

/// What [`ContactForce::overlapping`] found in a chunk: the particles to visit (`visit`, the
/// chunk's indices l, ascending: those with an overlapping pair or a collider candidate),
/// and for the q-th of them its overlapping partners j (ascending) in `partners`, from
/// `start[q]` to `start[q + 1]`.
#[derive(Default)]
pub(super) struct Overlapping {
    pub visit: Vec<u32>,
    pub start: Vec<u32>,
    pub partners: Vec<u32>,
    /// Room of the scan: the overlapping entries (l, j).
    hits: Vec<(u32, u32)>,
    /// The chunk's first non-finite position coordinate (3 i + k), when asked.
    pub bad: Option<usize>,
}

impl ContactForce<'_> {
    /// The listed pairs of the chunk whose first particle is `first` (its list rows `rows`)
    /// that overlap at positions `x` (m), and the particles to visit, given the chunk's
    /// collider candidates `walls` ((particle, collider), sorted by particle), into `out`;
    /// with `check`, the chunk's first non-finite position coordinate.
    #[inline(never)]
    pub(super) fn overlapping(
        &self,
        rows: &Rows,
        first: usize,
        x: &[f64],
        walls: &[(usize, usize)],
        check: bool,
        out: &mut Overlapping,
    ) {
        match self.domain.periodic_box() {
            Some(p) => self.scan(rows, first, x, walls, out, |d| p.min_image(d)),
            None => self.scan(rows, first, x, walls, out, |d| d),
        }
        out.bad = None;
        if check {
            let part = &x[3 * first..3 * (first + rows.len())];
            out.bad = first_non_finite(part).map(|(k, _)| 3 * first + k);
        }
    }

    /// [`Self::overlapping`] with the displacement's minimum image `image` (the identity in
    /// an open domain): one loop for each, with nothing to decide inside.
    ///
    /// The loop runs over the chunk's entries, not its particles: a particle of a gas has
    /// zero, one or a few partners, and a loop over each particle's row ended at a branch
    /// the processor could not foresee (about one missed guess a particle, ~15 cycles, where
    /// the test itself takes a few). Each entry's particle l is read from the rows' own
    /// [`Rows::owner`], made once when the rows are (made here at each pass, from the rows'
    /// starts, the 10⁵ gas of `benchmarks/granular_gas.py` was 4–7 % slower, 10⁶ 6 %:
    /// interleaved pairs of runs).
    #[inline(always)]
    fn scan(
        &self,
        rows: &Rows,
        first: usize,
        x: &[f64],
        walls: &[(usize, usize)],
        out: &mut Overlapping,
        image: impl Fn([f64; 3]) -> [f64; 3],
    ) {
        let (radius, partners, owner) = (self.radius, rows.partners(), rows.owner());
        assert_eq!(owner.len(), partners.len(), "the list's rows are sealed at their making");
        // the overlapping entries (l, j), in the rows' order
        let hits = &mut out.hits;
        hits.clear();
        for (k, (&j, &l)) in partners.iter().zip(owner).enumerate() {
            if let Some(&ahead) = partners.get(k + AHEAD) {
                prefetch(&x[3 * ahead as usize]);
                prefetch(&radius[ahead as usize]);
            }
            let (i, j) = (first + l as usize, j as usize);
            let (xi, xj) = (&x[3 * i..3 * i + 3], &x[3 * j..3 * j + 3]);
            // (`ContactForce::overlaps`, term for term)
            let d = image([xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]]);
            let reach = radius[i] + radius[j] + 0.0;
            if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach {
                hits.push((l as u32, j as u32));
            }
        }
        // the particles to visit: those of the hits and the collider candidates, merged
        out.visit.clear();
        out.start.clear();
        out.partners.clear();
        out.start.push(0);
        let mut walls = walls.iter().map(|w| (w.0 - first) as u32).peekable();
        let mut hits = out.hits.iter().peekable();
        loop {
            let l = match (hits.peek(), walls.peek()) {
                (Some(h), Some(&w)) => h.0.min(w),
                (Some(h), None) => h.0,
                (None, Some(&w)) => w,
                (None, None) => break,
            };
            while let Some(&(_, j)) = hits.next_if(|h| h.0 == l) {
                out.partners.push(j);
            }
            while walls.next_if(|&w| w == l).is_some() {}
            out.visit.push(l);
            out.start.push(out.partners.len() as u32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::contact_force::{Bodies, ContactForceModel};
    use crate::collide::{Domain, Material, Periodic};
    use crate::forces::testing::Rng;

    /// The scan against the pass's own test, row by row: particles strewn about a periodic cell's
    /// corner (so that pairs overlap through its sides) or an open space, rows of 0 to 5 listed
    /// partners drawn at random (empty ones first, between and last), collider candidates at
    /// some particles with no pair: the overlapping entries, in the rows' order, and the
    /// particles visited (those with an overlapping pair or a candidate, each once) are what
    /// testing each listed pair with `ContactForce::overlaps` finds; a non-finite coordinate
    /// is found where it is, and the chunk's first one.
    #[test]
    fn the_scan_finds_the_overlapping_listed_pairs_and_the_particles_to_visit() {
        let mut rng = Rng::new(5);
        let (first, len, n) = (100, 300, 700);
        let model = ContactForceModel::new(1e4, None);
        let radius: Vec<f64> = (0..n).map(|_| rng.uniform(0.03, 0.07)).collect();
        let inv_mass = vec![1.0; n];
        let cell = Periodic::new([0.0; 3], [1.0; 3], [true; 3]).unwrap();
        for domain in [Domain::periodic(3, cell).unwrap(), Domain::open(3).unwrap()] {
            // (within 0.15 of the cell's corner, through its sides: the listed pairs often overlap)
            let mut x: Vec<f64> = rng.vec(3 * n, -0.15, 0.15).iter().map(|c| c.rem_euclid(1.0)).collect();
            let bodies = Bodies {
                global: Material::new(0.5, 0.0).unwrap(),
                own: None,
                own_friction: false,
                radius: &radius,
                inv_mass: &inv_mass,
                colliders: &[],
                domain: &domain,
                omega: &[],
                filter: None,
            };
            let force = ContactForce::new(&model, bodies);
            let mut each = Vec::new();
            for l in 0..len {
                let count = if l < 3 || l >= len - 4 {
                    0
                } else {
                    rng.uniform(0.0, 6.0) as usize
                };
                let i = first + l;
                let mut row: Vec<u32> = (0..count)
                    .map(|_| (i + 1 + rng.uniform(0.0, (n - i - 1) as f64) as usize) as u32)
                    .collect();
                row.sort_unstable();
                row.dedup();
                each.push(row);
            }
            let rows = Rows::from_rows(&each);
            let walls: Vec<(usize, usize)> = [5, 5, 40, len - 1].iter().map(|&l| (first + l, 0)).collect();
            let mut out = Overlapping::default();
            force.overlapping(&rows, first, &x, &walls, true, &mut out);
            let (mut visit, mut start, mut partners) = (Vec::new(), vec![0], Vec::new());
            for l in 0..len {
                let i = first + l;
                let xi = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
                let hits: Vec<u32> = rows
                    .of(l)
                    .iter()
                    .copied()
                    .filter(|&j| force.overlaps(xi, radius[i], j as usize, &x))
                    .collect();
                if !hits.is_empty() || walls.iter().any(|w| w.0 == i) {
                    visit.push(l as u32);
                    partners.extend(hits);
                    start.push(partners.len() as u32);
                }
            }
            assert!(partners.len() > 20, "the draw has overlapping pairs: {}", partners.len());
            assert_eq!(out.visit, visit, "the particles visited");
            assert_eq!(out.start, start, "their rows' starts");
            assert_eq!(out.partners, partners, "their overlapping partners");
            assert_eq!(out.bad, None);
            // a non-finite coordinate in the chunk, another after it
            x[3 * (first + 250) + 1] = f64::NAN;
            x[3 * (first + 270)] = f64::INFINITY;
            x[3 * (first + len) + 2] = f64::NAN;
            force.overlapping(&rows, first, &x, &walls, true, &mut out);
            assert_eq!(out.bad, Some(3 * (first + 250) + 1));
            force.overlapping(&rows, first, &x, &walls, false, &mut out);
            assert_eq!(out.bad, None, "not asked");
        }
    }
}
