//! Per-vertex transfer vectors: what a bake produces.

use foundation::color::Rgb;
use foundation::sh::rotation::ShRotation;
use foundation::sh::{ShCoeffs, num_coeffs};

/// For each vertex and colour channel, `order²` SH coefficients `t_c` such that the vertex's
/// outgoing radiance under lighting `l_c` is `dot(t_c, l_c)`. Albedo and cosine are inside.
#[derive(Debug, Clone, PartialEq)]
pub struct TransferVectors {
    order: usize,
    vertex_count: usize,
    /// `data[(vertex * 3 + channel) * order² + k]`.
    data: Vec<f32>,
}

impl TransferVectors {
    pub fn zeros(order: usize, vertex_count: usize) -> Self {
        Self {
            order,
            vertex_count,
            data: vec![0.0; vertex_count * 3 * num_coeffs(order)],
        }
    }

    /// Wraps raw data laid out as `[vertex][channel][coefficient]`.
    pub fn from_raw(order: usize, vertex_count: usize, data: Vec<f32>) -> Option<Self> {
        (data.len() == vertex_count * 3 * num_coeffs(order)).then_some(Self {
            order,
            vertex_count,
            data,
        })
    }

    pub fn order(&self) -> usize {
        self.order
    }

    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Floats per vertex (`3 · order²`).
    pub fn stride(&self) -> usize {
        3 * num_coeffs(self.order)
    }

    pub fn as_slice(&self) -> &[f32] {
        &self.data
    }

    pub fn as_mut_slice(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// The transfer vector of `vertex` for `channel` (0 = R, 1 = G, 2 = B).
    pub fn vector(&self, vertex: usize, channel: usize) -> &[f32] {
        let n = num_coeffs(self.order);
        let start = (vertex * 3 + channel) * n;
        &self.data[start..start + n]
    }

    /// Outgoing radiance of `vertex` under `light` (`dot(t_c, l_c)` per channel). Bands the
    /// two do not share contribute nothing.
    pub fn radiance(&self, vertex: usize, light: &ShCoeffs<Rgb>) -> Rgb {
        let n = num_coeffs(self.order.min(light.order()));
        let l = &light.as_slice()[..n];
        let mut out = [0.0f32; 3];
        for (c, value) in out.iter_mut().enumerate() {
            let t = &self.vector(vertex, c)[..n];
            *value = t.iter().zip(l).map(|(t, l)| t * l[c]).sum();
        }
        Rgb::from(out)
    }

    /// Per vertex, the cosine-weighted fraction of its hemisphere that sees the sky, read from
    /// a *direct* transfer baked with `albedo`: its constant coefficient is `ρ Y₀` times that
    /// fraction (the bake adds the basis of every escaping cosine-distributed ray). Taken from
    /// the channel with the largest albedo; a black vertex (nothing to read) gets 1. The
    /// renderer's specular occlusion.
    pub fn unoccluded_fraction(&self, albedo: &[Rgb]) -> Vec<f32> {
        const Y00: f32 = 0.282_094_8;
        albedo
            .iter()
            .enumerate()
            .take(self.vertex_count())
            .map(|(v, rho)| {
                let c = (0..3)
                    .max_by(|a, b| rho[*a].total_cmp(&rho[*b]))
                    .unwrap_or(0);
                if rho[c] <= 1e-4 {
                    return 1.0;
                }
                (self.vector(v, c)[0] / (rho[c] * Y00)).clamp(0.0, 1.0)
            })
            .collect()
    }

    /// Per vertex, its bent normal: the mean unoccluded direction (cosine-weighted), read
    /// from a *direct* transfer's band-1 coefficients (the SH of `V(ω) max(0, n·ω)` are
    /// proportional to them; coefficients 1, 2, 3 go with x, y, z: CONVENTIONS.md), on the
    /// channel with the largest albedo. Where nothing is read (black, or fully occluded), the
    /// vertex normal.
    pub fn bent_normals(&self, albedo: &[Rgb], normals: &[glam::Vec3]) -> Vec<glam::Vec3> {
        albedo
            .iter()
            .zip(normals)
            .enumerate()
            .take(self.vertex_count())
            .map(|(v, (rho, n))| {
                let c = (0..3)
                    .max_by(|a, b| rho[*a].total_cmp(&rho[*b]))
                    .unwrap_or(0);
                if self.order < 2 || rho[c] <= 1e-4 {
                    return *n;
                }
                let t = self.vector(v, c);
                glam::Vec3::new(t[1], t[2], t[3])
                    .try_normalize()
                    .unwrap_or(*n)
            })
            .collect()
    }

    /// Scales the vectors of `vertex`, channel by channel.
    pub fn scale_vertex(&mut self, vertex: usize, factor: Rgb) {
        let n = num_coeffs(self.order);
        let (start, stride) = (vertex * self.stride(), self.stride());
        if let Some(vector) = self.data.get_mut(start..start + stride) {
            for (c, channel) in vector.chunks_exact_mut(n).enumerate() {
                channel.iter_mut().for_each(|x| *x *= factor[c]);
            }
        }
    }

    /// Turns the vectors of `vertices` by `rotation`: the transfer of those vertices' object
    /// turned rigidly with them. An object baked alone (nothing else to shadow or light it)
    /// turns exactly so: its transfer in the turned frame is the old one of `R⁻¹ ω`.
    pub fn rotate_vertices(&mut self, vertices: std::ops::Range<usize>, rotation: &ShRotation) {
        let n = num_coeffs(self.order);
        let start = vertices.start * self.stride();
        let end = vertices.end.min(self.vertex_count) * self.stride();
        for vector in self.data[start..end.max(start)].chunks_exact_mut(n) {
            let Some(coeffs) = ShCoeffs::from_vec(vector.to_vec()) else {
                continue;
            };
            vector.copy_from_slice(rotation.rotate(&coeffs).with_order(self.order).as_slice());
        }
    }

    /// Element-wise sum (direct + indirect = full transfer).
    /// Each vertex's vectors times its albedo, channel by channel.
    pub(crate) fn scaled_per_vertex(&self, albedo: &[Rgb]) -> TransferVectors {
        let mut out = self.clone();
        let per_channel = self.stride() / 3;
        for (vector, rho) in out.data.chunks_exact_mut(self.stride()).zip(albedo) {
            for (c, channel) in vector.chunks_exact_mut(per_channel).enumerate() {
                for x in channel {
                    *x *= rho[c];
                }
            }
        }
        out
    }

    /// Adds `other` in place.
    pub(crate) fn add(&mut self, other: &TransferVectors) {
        assert_eq!(
            (self.order, self.vertex_count),
            (other.order, other.vertex_count)
        );
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            *a += b;
        }
    }

    /// `0 + t` (what adding to zeros gives: `-0` becomes `+0`), without the zeros.
    pub(crate) fn plus_zero(mut self) -> Self {
        for x in &mut self.data {
            *x += 0.0;
        }
        self
    }

    pub fn sum(&self, other: &TransferVectors) -> TransferVectors {
        assert_eq!(
            (self.order, self.vertex_count),
            (other.order, other.vertex_count)
        );
        TransferVectors {
            order: self.order,
            vertex_count: self.vertex_count,
            data: self
                .data
                .iter()
                .zip(&other.data)
                .map(|(a, b)| a + b)
                .collect(),
        }
    }

    /// The same transfer truncated to `order` bands (fewer coefficients per vertex).
    pub fn truncated(&self, order: usize) -> TransferVectors {
        let order = order.min(self.order);
        let (n_old, n_new) = (num_coeffs(self.order), num_coeffs(order));
        let mut data = Vec::with_capacity(self.vertex_count * 3 * n_new);
        for chunk in self.data.chunks_exact(n_old) {
            data.extend_from_slice(&chunk[..n_new]);
        }
        TransferVectors {
            order,
            vertex_count: self.vertex_count,
            data,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::sh::ShBasis;
    use glam::{Quat, Vec3};

    /// A vertex whose transfer is a single direction `d` (the SH of a delta there) turned by
    /// `R` becomes the delta at `R d`, the turned object's direction: the convention a turned
    /// model's lighting depends on. The vertices outside the range keep theirs.
    #[test]
    fn rotated_transfer_follows_the_turned_direction() {
        let order = 5;
        let basis = ShBasis::new(order).unwrap();
        let d = Vec3::new(0.3, 0.8, -0.52).normalize();
        let delta = basis.eval_vec(d);
        let data: Vec<f32> = (0..2 * 3).flat_map(|_| delta.clone()).collect();
        let mut t = TransferVectors::from_raw(order, 2, data).unwrap();
        let turn = Quat::from_euler(glam::EulerRot::YXZ, 1.9, -0.7, 0.4);
        let rotation = ShRotation::new(glam::Mat3::from_quat(turn), order).unwrap();
        t.rotate_vertices(1..2, &rotation);
        let turned = basis.eval_vec(turn * d);
        for c in 0..3 {
            for (k, (a, b)) in t.vector(1, c).iter().zip(&turned).enumerate() {
                assert!((a - b).abs() < 1e-4, "coefficient {k}: {a} against {b}");
            }
            assert_eq!(t.vector(0, c), delta.as_slice());
        }
    }

    #[test]
    fn radiance_is_a_per_channel_dot_product() {
        let order = 2;
        let data: Vec<f32> = (0..2 * 3 * 4).map(|i| i as f32).collect();
        let t = TransferVectors::from_raw(order, 2, data).unwrap();
        let light = ShCoeffs::from_vec(vec![
            Rgb::new(1.0, 0.0, 0.0),
            Rgb::new(0.0, 1.0, 0.0),
            Rgb::new(0.0, 0.0, 1.0),
            Rgb::ZERO,
        ])
        .unwrap();
        // Vertex 1: R vector = 12..16, G = 16..20, B = 20..24.
        assert_eq!(t.radiance(1, &light), Rgb::new(12.0, 17.0, 22.0));
        let cut = t.truncated(1);
        assert_eq!(cut.vector(1, 2), &[20.0]);
        assert_eq!(t.sum(&t).vector(0, 0), &[0.0, 2.0, 4.0, 6.0]);
        assert!(TransferVectors::from_raw(2, 3, vec![0.0; 5]).is_none());
    }
}
