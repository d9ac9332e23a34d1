//! What the traversals' tests share: a soup of random triangles and the answer of testing
//! every one of them.

use super::Skip;
use super::packed_corners;
use super::wide::{Floors, moller_trumbore};
use crate::mesh::TriangleMesh;
use glam::Vec3;
use rand_core::Rng;

/// 3000 triangles in a cube of half-size 4: most small, one in ten long and thin (the builder
/// pre-splits those). Its random stream goes on to draw the rays.
pub(super) struct Soup {
    pub(super) mesh: TriangleMesh,
    rng: rand_pcg::Pcg32,
}

impl Soup {
    pub(super) fn new(seed: u64) -> Self {
        let mut soup = Self {
            mesh: TriangleMesh::default(),
            rng: rand_pcg::Pcg32::new(seed, 0),
        };
        for k in 0..3000u32 {
            let centre = soup.point(4.0);
            let size = if k % 10 == 0 { 3.0 } else { 0.2 };
            for _ in 0..3 {
                let corner = centre + soup.point(size);
                soup.mesh.positions.push(corner);
                soup.mesh.normals.push(Vec3::Y);
            }
            soup.mesh.triangles.push([3 * k, 3 * k + 1, 3 * k + 2]);
        }
        soup
    }

    fn uniform(&mut self) -> f32 {
        (self.rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }

    /// A point uniform in the cube of half-size `scale` about the origin.
    pub(super) fn point(&mut self, scale: f32) -> Vec3 {
        let unit = Vec3::new(self.uniform(), self.uniform(), self.uniform());
        unit * 2.0 * scale - Vec3::splat(scale)
    }

    /// The `k`-th test direction: along an axis (with negative zeros) for some `k`, random
    /// otherwise.
    pub(super) fn direction(&mut self, k: u32) -> Vec3 {
        match k % 7 {
            0 => Vec3::X,
            1 => Vec3::new(-0.0, -1.0, -0.0),
            _ => (self.point(1.0) - self.point(1.0) * 0.01).normalize_or(Vec3::Z),
        }
    }

    /// The closest hit `(t, triangle)` by testing every triangle, with the acceptance rule
    /// written out: a back no nearer than [`super::wide::MIN_BOX_DISTANCE`], a front from that far behind
    /// the origin (at 0), equidistant triangles to the lowest index.
    pub(super) fn closest(
        &self,
        origin: Vec3,
        direction: Vec3,
        tmax: f32,
        skip: Skip,
    ) -> Option<(f32, u32)> {
        (0..self.mesh.triangle_count())
            .filter(|t| Skip::Triangle(*t as u32) != skip)
            .map(|t| (self.distance(t, origin, direction, tmax), t as u32))
            .filter(|(t, _)| t.is_finite())
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    fn distance(&self, t: usize, origin: Vec3, direction: Vec3, tmax: f32) -> f32 {
        let ([a, b, c], _) = packed_corners(&self.mesh, t);
        let (u, v, d, inv_det) = moller_trumbore(
            origin.to_array(),
            direction.to_array(),
            a.to_array(),
            (b - a).to_array(),
            (c - a).to_array(),
        );
        let floors = Floors::new(0.0);
        let floor = if inv_det > 0.0 {
            floors.front
        } else {
            floors.back
        };
        // A front hit behind the origin counts at +0 (as `maxps` gives it).
        let distance = if d > 0.0 { d } else { 0.0 };
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && d >= floor && distance <= tmax {
            distance
        } else {
            f32::INFINITY
        }
    }
}
