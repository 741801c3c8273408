//! A set of particles kept as flags and as a list: marking and asking are O(1), and walking
//! the marked ones or clearing them costs what was marked, not N (a step of a gas marks a
//! few hundred of 10⁵ particles).

/// Particles marked, by index: a flag per particle and the list of those marked (each once).
#[derive(Debug, Default, Clone)]
pub(crate) struct Marks {
    flag: Vec<bool>,
    list: Vec<usize>,
    sorted: bool,
}

impl Marks {
    /// None of `n` particles marked (all of them with `all`).
    pub fn reset(&mut self, n: usize, all: bool) {
        if self.flag.len() != n || self.list.len() > n / 8 {
            self.flag.clear();
            self.flag.resize(n, false);
        } else {
            for &q in &self.list {
                self.flag[q] = false;
            }
        }
        self.list.clear();
        self.sorted = true;
        if all {
            self.mark_all();
        }
    }

    /// Marks particle q; true if it was not marked before.
    #[inline]
    pub fn mark(&mut self, q: usize) -> bool {
        if self.flag[q] {
            return false;
        }
        self.flag[q] = true;
        self.sorted &= self.list.last().is_none_or(|&l| l < q);
        self.list.push(q);
        true
    }

    /// Marks every particle.
    pub fn mark_all(&mut self) {
        self.flag.fill(true);
        self.list.clear();
        self.list.extend(0..self.flag.len());
        self.sorted = true;
    }

    /// Whether particle q is marked.
    #[inline]
    pub fn get(&self, q: usize) -> bool {
        self.flag[q]
    }

    /// The marked particles in ascending order.
    pub fn sorted(&mut self) -> &[usize] {
        if !self.sorted {
            self.list.sort_unstable();
            self.sorted = true;
        }
        &self.list
    }
}

#[cfg(test)]
mod tests {
    use super::Marks;

    #[test]
    fn marks_are_listed_once_in_order_and_cleared_by_the_list() {
        let mut m = Marks::default();
        m.reset(10, false);
        assert!(m.mark(7) && m.mark(2) && !m.mark(7) && m.mark(9));
        assert_eq!(m.sorted(), &[2, 7, 9]);
        assert!(m.get(2) && !m.get(3));
        m.reset(10, false);
        assert!(m.sorted().is_empty() && (0..10).all(|q| !m.get(q)));
        m.reset(4, true);
        assert_eq!(m.sorted(), &[0, 1, 2, 3]);
        assert!(!m.mark(1));
    }
}
