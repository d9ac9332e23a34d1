//! Spherical Gaussian smoothing of a cube map, evaluated at the icosahedron vertices
//! (thesis 4.3.3, "Spherical Function Sampling"). Each vertex's kernel footprint — the texels
//! within three standard deviations, found by culling each face to the kernel's bounding box —
//! is computed once; smoothing a map is then a sparse weighted sum.
//!
//! A footprint is stored as its rows on each face (runs of consecutive texels), cut into
//! blocks of [`LANES`] texels with zero weights where a row does not fill its last block: the
//! sum then reads the map in contiguous vectors instead of gathering texel by texel.

use super::lanes::load;
use crate::cubemap::{CubeGeometry, CubeMap};
use foundation::Rgb;
use glam::Vec3;
use wide::f32x8;

/// Texels per block: two 4-wide vectors.
const LANES: usize = 8;

#[derive(Debug, Clone)]
pub(crate) struct GaussianSmoothing {
    /// `block_starts[v]..block_starts[v + 1]` indexes the blocks of point `v`.
    block_starts: Vec<u32>,
    /// The first texel of each block: block `b` covers texels `texels[b]..texels[b] + LANES`
    /// (of the map padded to at least [`LANES`] texels) with weights `weights[b · LANES..]`.
    texels: Vec<u32>,
    /// Zero where a block runs past its row.
    weights: Vec<f32>,
    /// The texel count of the geometry the smoothing was built for.
    texel_count: usize,
}

impl GaussianSmoothing {
    /// Kernel `exp(-θ² / 2σ²)` around each of `points`, truncated at `3σ`, with weights that
    /// include each texel's solid angle and sum to 1.
    pub(crate) fn new(geometry: &CubeGeometry, points: &[Vec3], sigma: f32) -> Self {
        let mut smoothing = Self {
            block_starts: vec![0],
            texels: Vec::new(),
            weights: Vec::new(),
            texel_count: geometry.texel_count(),
        };
        let (mut footprint, mut weights) = (Vec::new(), Vec::new());
        for p in points {
            // At least the texel under the point, however small σ is.
            geometry.texels_within(*p, (3.0 * sigma).max(1e-4), &mut footprint);
            if footprint.is_empty() {
                footprint.push(geometry.texel_of(*p) as u32);
            }
            weights.clear();
            weights.extend(footprint.iter().map(|&t| {
                let theta = geometry.directions()[t as usize]
                    .dot(*p)
                    .clamp(-1.0, 1.0)
                    .acos();
                (-theta * theta / (2.0 * sigma * sigma)).exp() * geometry.solid_angles()[t as usize]
            }));
            let total: f32 = weights.iter().sum();
            for w in &mut weights {
                *w /= total;
            }
            smoothing.push_footprint(&footprint, &weights);
        }
        smoothing
    }

    /// Appends one point's footprint (texels in increasing order within each row) as blocks.
    fn push_footprint(&mut self, texels: &[u32], weights: &[f32]) {
        let span = self.texel_count.max(LANES);
        let mut i = 0;
        while i < texels.len() {
            let mut len = 1;
            while i + len < texels.len() && texels[i + len] == texels[i] + len as u32 {
                len += 1;
            }
            // The row's blocks may not read past the map: they then start earlier, the row's
            // weights placed after zeros.
            let padded = len.next_multiple_of(LANES);
            let start = (texels[i] as usize).min(span - padded);
            let front = texels[i] as usize - start;
            let first = self.weights.len();
            self.weights.resize(first + padded, 0.0);
            self.weights[first + front..first + front + len].copy_from_slice(&weights[i..i + len]);
            self.texels
                .extend((start..start + padded).step_by(LANES).map(|t| t as u32));
            i += len;
        }
        self.block_starts.push(self.texels.len() as u32);
    }

    /// The smoothed values (one per texel of the geometry) at each point: for one channel, such
    /// as luminance, a third of the work of [`Self::apply`].
    pub(crate) fn apply_scalar(&self, values: &[f32], out: &mut Vec<f32>) {
        assert_eq!(values.len(), self.texel_count, "one value per texel");
        let mut padded = [0.0; LANES];
        let values = if values.len() < LANES {
            padded[..values.len()].copy_from_slice(values);
            &padded[..]
        } else {
            values
        };
        out.clear();
        out.extend(self.block_starts.windows(2).map(|r| {
            // One 8-wide sum (two 4-wide halves where the CPU has no 8-wide vectors).
            let mut sum = f32x8::ZERO;
            let blocks = r[0] as usize..r[1] as usize;
            let weights =
                self.weights[blocks.start * LANES..blocks.end * LANES].chunks_exact(LANES);
            for (&t, w) in self.texels[blocks].iter().zip(weights) {
                let texels = &values[t as usize..t as usize + LANES];
                sum = load(texels).mul_add(load(w), sum);
            }
            sum.reduce_add()
        }));
    }

    /// The smoothed map at each point.
    pub(crate) fn apply(&self, map: &CubeMap, out: &mut Vec<Rgb>) {
        assert_eq!(
            map.texels().len(),
            self.texel_count,
            "a map of the geometry"
        );
        let mut padded = [Rgb::ZERO; LANES];
        let texels = if map.texels().len() < LANES {
            padded[..map.texels().len()].copy_from_slice(map.texels());
            &padded[..]
        } else {
            map.texels()
        };
        out.clear();
        out.extend(self.block_starts.windows(2).map(|r| {
            let mut sum = Rgb::ZERO;
            for b in r[0] as usize..r[1] as usize {
                let t = self.texels[b] as usize;
                let weights = &self.weights[b * LANES..(b + 1) * LANES];
                for (t, w) in texels[t..t + LANES].iter().zip(weights) {
                    sum += *t * *w;
                }
            }
            sum
        }));
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

    /// The padded runs give the kernel's plain sparse sum (texel by texel), on maps smaller
    /// than one vector, with footprints at both ends of the texel array, and wide kernels.
    #[test]
    fn runs_give_the_plain_weighted_sum() {
        for (size, sigma) in [(1, 0.3), (2, 0.05), (3, 0.4), (32, 0.035), (32, 0.2)] {
            let geometry = CubeGeometry::new(size);
            let count = geometry.texel_count();
            // Points at the first and last texels, and scattered ones.
            let mut points = vec![
                geometry.directions()[0],
                geometry.directions()[count - 1],
                geometry.directions()[count - 1 - size / 2],
            ];
            points.extend((0..40).map(|k| {
                let k = k as f32;
                Vec3::new((k * 1.7).sin(), (k * 0.9).cos(), (k * 2.3).sin() + 0.1).normalize()
            }));
            let smoothing = GaussianSmoothing::new(&geometry, &points, sigma);
            let values: Vec<f32> = (0..count)
                .map(|t| 1.0 + ((t * 7919) % 101) as f32)
                .collect();
            let mut out = Vec::new();
            smoothing.apply_scalar(&values, &mut out);
            let mut footprint = Vec::new();
            for (p, got) in points.iter().zip(&out) {
                geometry.texels_within(*p, 3.0 * sigma, &mut footprint);
                if footprint.is_empty() {
                    footprint.push(geometry.texel_of(*p) as u32);
                }
                let (mut sum, mut total) = (0.0f64, 0.0f64);
                for &t in &footprint {
                    // The angle as the kernel takes it (acos of the f32 cosine).
                    let cos = geometry.directions()[t as usize].dot(*p).clamp(-1.0, 1.0);
                    let theta = cos.acos() as f64;
                    let w = (-theta * theta / (2.0 * (sigma * sigma) as f64)).exp()
                        * geometry.solid_angles()[t as usize] as f64;
                    sum += w * values[t as usize] as f64;
                    total += w;
                }
                let want = sum / total;
                assert!(
                    (*got as f64 - want).abs() <= 1e-5 * want,
                    "size {size}, σ {sigma}: {got} vs {want}"
                );
            }
        }
    }
}
