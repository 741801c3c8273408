//! Stage 2 of the pair pass (`pairs.rs`): what chunks owe particles of later chunks,
//! sorted and indexed by receiving chunk, and received by each chunk in ascending order of
//! sending chunk, so that every particle's force is summed in the same order on any number
//! of threads.

use rayon::prelude::*;

use super::CHUNK;

/// The forces chunks send to particles of later chunks (stage 2 of the pair pass), kept
/// between evaluations so that a pass allocates nothing once warm.
#[derive(Default)]
pub(super) struct Exchange {
    /// Per chunk: (j, F n) for each contact force, N, it owes particle j of a later chunk;
    /// after stage 1, sorted by j's chunk (stably: the order found within a chunk kept).
    pub(super) sent: Vec<Vec<(u32, [f64; 3])>>,
    /// Per receiving chunk d: (chunk c, start, end) of what `sent[c]` owes d, ascending c.
    inbox: Vec<Vec<(u32, u32, u32)>>,
}

impl Exchange {
    /// Subtracts from chunk `d`'s forces `fc` (N, 3 per particle of the chunk) what the
    /// earlier chunks sent it, in ascending order of sending chunk.
    #[inline]
    pub(super) fn receive(&self, d: usize, fc: &mut [f64]) {
        let first = d * CHUNK;
        for &(c, start, end) in &self.inbox[d] {
            for (j, fv) in &self.sent[c as usize][start as usize..end as usize] {
                let l = *j as usize - first;
                for k in 0..3 {
                    fc[3 * l + k] -= fv[k];
                }
            }
        }
    }

    /// How many forces the last pass sent between chunks.
    #[cfg(test)]
    pub(super) fn sent_count(&self) -> usize {
        self.sent.iter().map(Vec::len).sum()
    }

    /// Sorts each outbox by receiving chunk and indexes the runs by receiver.
    pub(super) fn index(&mut self, chunks: usize) {
        self.sent.par_iter_mut().for_each(|s| s.sort_by_key(|e| e.0 as usize / CHUNK));
        self.inbox.resize_with(chunks, Vec::new);
        self.inbox.iter_mut().for_each(Vec::clear);
        for (c, sent) in self.sent.iter().enumerate() {
            let mut start = 0;
            while start < sent.len() {
                let d = sent[start].0 as usize / CHUNK;
                let end = start + sent[start..].partition_point(|e| e.0 as usize / CHUNK == d);
                self.inbox[d].push((c as u32, start as u32, end as u32));
                start = end;
            }
        }
    }
}
