//! The interreflection operator and one Neumann-series bounce.

use super::TransferVectors;
use foundation::color::Rgb;
use foundation::infra::prefetch::prefetch_range;
use rayon::prelude::*;

/// How many operator entries ahead the bounce asks the cache for the row it will gather.
const GATHER_AHEAD: usize = 6;

/// Sparse vertex-to-vertex operator `W`: `W[v][j]` is the fraction of vertex `v`'s
/// cosine-distributed rays that land on the front of a triangle, weighted by the barycentric
/// weight of `j` at the landing point. One bounce is `T' = diag(ρ) W T`.
///
/// Stored as consecutive blocks of compressed rows, exactly as the tracing pass produced
/// them, so the (large) operator is never copied.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InterreflectionOperator {
    blocks: Vec<OperatorBlock>,
}

/// Compressed rows of `rows` consecutive vertices.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct OperatorBlock {
    /// `row_starts[r]..row_starts[r + 1]` indexes `columns`/`weights` of the block's row `r`.
    pub row_starts: Vec<u32>,
    pub columns: Vec<u32>,
    pub weights: Vec<f32>,
}

impl OperatorBlock {
    pub(crate) fn new() -> Self {
        Self {
            row_starts: vec![0],
            ..Default::default()
        }
    }

    pub(crate) fn rows(&self) -> usize {
        self.row_starts.len() - 1
    }

    /// Appends a row given as `(column, weight)` pairs sorted by column; equal columns merge.
    pub(crate) fn push_sorted_row(&mut self, entries: &[(u32, f32)]) {
        let row_start = self.columns.len();
        for &(j, w) in entries {
            let last = self.columns.len().wrapping_sub(1);
            if self.columns.len() > row_start && self.columns[last] == j {
                self.weights[last] += w;
            } else {
                self.columns.push(j);
                self.weights.push(w);
            }
        }
        self.row_starts.push(self.columns.len() as u32);
    }

    /// Releases the growth slack of the entry vectors.
    pub(crate) fn shrink_to_fit(&mut self) {
        self.columns.shrink_to_fit();
        self.weights.shrink_to_fit();
    }

    fn row(&self, r: usize) -> (&[u32], &[f32]) {
        let range = self.row_starts[r] as usize..self.row_starts[r + 1] as usize;
        (&self.columns[range.clone()], &self.weights[range])
    }
}

impl InterreflectionOperator {
    /// Blocks covering consecutive vertex ranges, in order.
    pub(crate) fn from_blocks(blocks: Vec<OperatorBlock>) -> Self {
        Self { blocks }
    }

    /// The blocks, in order.
    pub(crate) fn into_blocks(self) -> Vec<OperatorBlock> {
        self.blocks
    }

    /// The blocks, in order.
    pub(crate) fn blocks(&self) -> &[OperatorBlock] {
        &self.blocks
    }

    /// Number of stored (vertex, vertex) weights.
    pub fn entries(&self) -> usize {
        self.blocks.iter().map(|b| b.columns.len()).sum()
    }

    /// Sum of row `v`: the fraction of `v`'s (cosine-weighted) hemisphere that sees front faces.
    #[cfg(test)]
    pub(crate) fn row_sum(&self, mut v: usize) -> f32 {
        for block in &self.blocks {
            if v < block.rows() {
                return block.row(v).1.iter().sum();
            }
            v -= block.rows();
        }
        panic!("row out of range");
    }

    /// One bounce: `out_c(v) = ρ_c(v) Σ_j W[v][j] t_c(j)`.
    pub fn apply(&self, transfer: &TransferVectors, albedo: &[Rgb]) -> TransferVectors {
        let stride = transfer.stride();
        let per_channel = stride / 3;
        let input = transfer.as_slice();
        let mut out = TransferVectors::zeros(transfer.order(), transfer.vertex_count());
        // Split the output into the blocks' vertex ranges.
        let mut rest = out.as_mut_slice();
        let mut work = Vec::with_capacity(self.blocks.len());
        let mut first_vertex = 0;
        for block in &self.blocks {
            let (head, tail) = rest.split_at_mut(block.rows() * stride);
            work.push((block, first_vertex, head));
            first_vertex += block.rows();
            rest = tail;
        }
        // Each row is summed apart and its output written once: adding into the fresh zeros
        // would fault twice per page (read, then write), each write fault flushing every
        // thread's TLB.
        work.into_par_iter()
            .for_each(|(block, first_vertex, out_rows)| {
                let mut row_sum = vec![0.0f32; stride];
                let mut entry = 0;
                for (r, row_out) in out_rows.chunks_exact_mut(stride).enumerate() {
                    row_sum.fill(0.0);
                    let (columns, weights) = block.row(r);
                    for (&j, &w) in columns.iter().zip(weights) {
                        // The rows gathered are scattered over the whole transfer: ask for
                        // one a few entries ahead so that its misses overlap this one's.
                        if let Some(&ahead) = block.columns.get(entry + GATHER_AHEAD) {
                            let row = input.as_ptr().wrapping_add(ahead as usize * stride);
                            prefetch_range(row, stride);
                        }
                        entry += 1;
                        let src = &input[j as usize * stride..(j as usize + 1) * stride];
                        for (o, s) in row_sum.iter_mut().zip(src) {
                            *o += w * s;
                        }
                    }
                    let rho = albedo[first_vertex + r];
                    for (c, (out, sum)) in row_out
                        .chunks_exact_mut(per_channel)
                        .zip(row_sum.chunks_exact(per_channel))
                        .enumerate()
                    {
                        for (o, s) in out.iter_mut().zip(sum) {
                            *o = s * rho[c];
                        }
                    }
                }
            });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn applies_weights_then_albedo() {
        // Vertex 0 sees vertex 1 with weight 0.5 (given as two hits); vertex 1 sees nothing.
        let mut first = OperatorBlock::new();
        first.push_sorted_row(&[(1, 0.25), (1, 0.25)]);
        let mut second = OperatorBlock::new();
        second.push_sorted_row(&[]);
        let op = InterreflectionOperator::from_blocks(vec![first, second]);
        let t = TransferVectors::from_raw(1, 2, vec![0.0, 0.0, 0.0, 2.0, 4.0, 6.0]).unwrap();
        let albedo = [Rgb::new(0.5, 1.0, 0.25), Rgb::ONE];
        let out = op.apply(&t, &albedo);
        assert_eq!(out.as_slice(), &[0.5, 2.0, 0.75, 0.0, 0.0, 0.0]);
        assert_eq!(op.row_sum(0), 0.5);
        assert_eq!(op.row_sum(1), 0.0);
        assert_eq!(op.entries(), 1);
    }
}
