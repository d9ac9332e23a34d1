//! Spherical Gaussian smoothing of a cube map, evaluated at the icosahedron vertices
//! (thesis 4.3.3, "Spherical Function Sampling"). Each vertex's kernel footprint — the texels
//! within three standard deviations, found by culling each face to the kernel's bounding box —
//! is computed once; smoothing a map is then a sparse weighted sum.

use crate::cubemap::{CubeGeometry, CubeMap};
use foundation::Rgb;
use glam::Vec3;

#[derive(Debug, Clone)]
pub(crate) struct GaussianSmoothing {
    /// `row_starts[v]..row_starts[v + 1]` indexes `texels`/`weights` of vertex `v`.
    row_starts: Vec<u32>,
    texels: Vec<u32>,
    weights: Vec<f32>,
}

impl GaussianSmoothing {
    /// Kernel `exp(-θ² / 2σ²)` around each of `points`, truncated at `3σ`, with weights that
    /// include each texel's solid angle and sum to 1.
    pub(crate) fn new(geometry: &CubeGeometry, points: &[Vec3], sigma: f32) -> Self {
        let mut row_starts = Vec::with_capacity(points.len() + 1);
        row_starts.push(0);
        let (mut texels, mut weights) = (Vec::new(), Vec::new());
        let mut footprint = Vec::new();
        for p in points {
            // At least the texel under the point, however small σ is.
            geometry.texels_within(*p, (3.0 * sigma).max(1e-4), &mut footprint);
            if footprint.is_empty() {
                footprint.push(geometry.texel_of(*p) as u32);
            }
            let start = weights.len();
            for &t in &footprint {
                let theta = geometry.directions()[t as usize]
                    .dot(*p)
                    .clamp(-1.0, 1.0)
                    .acos();
                texels.push(t);
                weights.push(
                    (-theta * theta / (2.0 * sigma * sigma)).exp()
                        * geometry.solid_angles()[t as usize],
                );
            }
            let total: f32 = weights[start..].iter().sum();
            for w in &mut weights[start..] {
                *w /= total;
            }
            row_starts.push(texels.len() as u32);
        }
        Self {
            row_starts,
            texels,
            weights,
        }
    }

    /// The smoothed values (one per texel of the geometry) at each point: for one channel, such
    /// as luminance, a third of the work of [`Self::apply`]. Four partial sums per point, so
    /// that the additions do not wait on one another.
    pub(crate) fn apply_scalar(&self, values: &[f32], out: &mut Vec<f32>) {
        out.clear();
        out.extend(self.row_starts.windows(2).map(|r| {
            let range = r[0] as usize..r[1] as usize;
            let (texels, weights) = (&self.texels[range.clone()], &self.weights[range]);
            let mut sums = [0.0f32; 4];
            let quads = texels.chunks_exact(4).zip(weights.chunks_exact(4));
            for (t, w) in quads {
                for k in 0..4 {
                    sums[k] += values[t[k] as usize] * w[k];
                }
            }
            let rest = texels.len() / 4 * 4;
            for (t, w) in texels[rest..].iter().zip(&weights[rest..]) {
                sums[0] += values[*t as usize] * *w;
            }
            (sums[0] + sums[1]) + (sums[2] + sums[3])
        }));
    }

    /// The smoothed map at each point.
    pub(crate) fn apply(&self, map: &CubeMap, out: &mut Vec<Rgb>) {
        out.clear();
        let texels = map.texels();
        for v in 0..self.row_starts.len() - 1 {
            let range = self.row_starts[v] as usize..self.row_starts[v + 1] as usize;
            let mut sum = Rgb::ZERO;
            for (t, w) in self.texels[range.clone()].iter().zip(&self.weights[range]) {
                sum += texels[*t as usize] * *w;
            }
            out.push(sum);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preserves_constants_and_blurs_a_spike_symmetrically() {
        let geometry = CubeGeometry::new(32);
        let points = [Vec3::new(0.2, 0.3, -0.93).normalize(), Vec3::Y];
        let smoothing = GaussianSmoothing::new(&geometry, &points, 0.1);
        let mut out = Vec::new();
        smoothing.apply(&CubeMap::uniform(32, Rgb::splat(2.5)), &mut out);
        assert!(
            out.iter()
                .all(|c| (*c - Rgb::splat(2.5)).abs().max_element() < 1e-5)
        );
        // A single bright texel under point 0 shows up there, not at point 1.
        let mut map = CubeMap::uniform(32, Rgb::ZERO);
        map.texels_mut()[geometry.texel_of(points[0])] = Rgb::ONE;
        smoothing.apply(&map, &mut out);
        assert!(out[0].x > 0.0 && out[1].x == 0.0);
        // One channel at a time gives each channel of the whole (the sums in another order).
        let mut green = Vec::new();
        let map = CubeMap::from_fn(&geometry, |d| Rgb::new(1.0, 2.0 + d.x * d.y, 0.5));
        smoothing.apply(&map, &mut out);
        let values: Vec<f32> = map.texels().iter().map(|c| c.y).collect();
        smoothing.apply_scalar(&values, &mut green);
        for (g, c) in green.iter().zip(&out) {
            assert!((g - c.y).abs() <= 1e-6 * c.y, "{g} vs {}", c.y);
        }
    }
}
