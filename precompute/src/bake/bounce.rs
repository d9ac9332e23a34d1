//! The interreflection operator and one Neumann-series bounce.

use super::TransferVectors;
use crate::color::Rgb;
use rayon::prelude::*;

/// Sparse vertex-to-vertex operator `W` (compressed rows): `W[v][j]` is the fraction of vertex
/// `v`'s cosine-distributed rays that land on the front of a triangle, weighted by the
/// barycentric weight of `j` at the landing point. One bounce is `T' = diag(ρ) W T`.
#[derive(Debug, Clone, Default)]
pub struct InterreflectionOperator {
    row_starts: Vec<usize>,
    columns: Vec<u32>,
    weights: Vec<f32>,
}

impl InterreflectionOperator {
    pub fn from_rows(row_lengths: &[usize], columns: Vec<u32>, weights: Vec<f32>) -> Self {
        let mut row_starts = Vec::with_capacity(row_lengths.len() + 1);
        row_starts.push(0);
        for len in row_lengths {
            row_starts.push(row_starts.last().copied().unwrap_or(0) + len);
        }
        assert_eq!(row_starts.last().copied(), Some(columns.len()));
        assert_eq!(columns.len(), weights.len());
        Self {
            row_starts,
            columns,
            weights,
        }
    }

    /// Number of stored (vertex, vertex) weights.
    pub fn entries(&self) -> usize {
        self.columns.len()
    }

    /// Sum of row `v`: the fraction of `v`'s (cosine-weighted) hemisphere that sees front faces.
    pub fn row_sum(&self, v: usize) -> f32 {
        self.weights[self.row_starts[v]..self.row_starts[v + 1]].iter().sum()
    }

    /// One bounce: `out_c(v) = ρ_c(v) Σ_j W[v][j] t_c(j)`.
    pub fn apply(&self, transfer: &TransferVectors, albedo: &[Rgb]) -> TransferVectors {
        let stride = transfer.stride();
        let per_channel = stride / 3;
        let input = transfer.as_slice();
        let mut out = TransferVectors::zeros(transfer.order(), transfer.vertex_count());
        out.as_mut_slice()
            .par_chunks_mut(stride)
            .enumerate()
            .for_each(|(v, row_out)| {
                let range = self.row_starts[v]..self.row_starts[v + 1];
                for (&j, &w) in self.columns[range.clone()].iter().zip(&self.weights[range]) {
                    let src = &input[j as usize * stride..(j as usize + 1) * stride];
                    for (o, s) in row_out.iter_mut().zip(src) {
                        *o += w * s;
                    }
                }
                for c in 0..3 {
                    for o in &mut row_out[c * per_channel..(c + 1) * per_channel] {
                        *o *= albedo[v][c];
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
        // Vertex 0 sees vertex 1 with weight 0.5; vertex 1 sees nothing.
        let op = InterreflectionOperator::from_rows(&[1, 0], vec![1], vec![0.5]);
        let t = TransferVectors::from_raw(1, 2, vec![0.0, 0.0, 0.0, 2.0, 4.0, 6.0]).unwrap();
        let albedo = [Rgb::new(0.5, 1.0, 0.25), Rgb::ONE];
        let out = op.apply(&t, &albedo);
        assert_eq!(out.as_slice(), &[0.5, 2.0, 0.75, 0.0, 0.0, 0.0]);
        assert_eq!(op.row_sum(0), 0.5);
        assert_eq!(op.entries(), 1);
    }
}
