//! The path tracer: next-event estimation with environment importance sampling, combined by
//! multiple importance sampling (power heuristic) with cosine-weighted sampling of the surface.

use super::environment::EnvironmentLight;
use super::sampler::PathSampler;
use crate::bake::RAY_OFFSET_FRACTION;
use crate::bvh::{Hit, SceneBvh, Skip};
use crate::color::{Rgb, luminance};
use crate::sampling::{Frame, cosine_hemisphere};
use crate::scene::{NO_TEXTURE, SceneMesh};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// A shading point.
#[derive(Debug, Clone, Copy)]
pub struct SurfacePoint {
    pub position: Vec3,
    /// Interpolated vertex normal: the Lambertian cosine and sampling hemisphere.
    pub shading_normal: Vec3,
    /// Geometric normal on the front side: rays leave from this side.
    pub front_normal: Vec3,
    pub albedo: Rgb,
    /// Which triangles a ray leaving the point must not hit: the one it leaves, or, for a ray
    /// leaving a vertex, every triangle sharing the vertex (as in the bake).
    pub leaving: Skip,
}

/// Light reaching the first shading point directly from the environment, in luminance: what
/// is visible and what would be without occlusion (their ratio is the direct visibility).
#[derive(Debug, Clone, Copy, Default)]
pub struct DirectVisibility {
    pub visible: f32,
    pub unoccluded: f32,
}

/// One radiance estimate per call; everything it needs is borrowed.
pub struct Integrator<'a> {
    pub geometry: &'a SceneMesh,
    pub bvh: &'a SceneBvh,
    pub light: &'a EnvironmentLight<'a>,
    /// Indirect bounces after the first shading point (0: direct lighting only).
    pub bounces: u32,
    offset: f32,
    front_normals: Vec<Vec3>,
    /// Per triangle, its texture in `geometry.textures` or [`NO_TEXTURE`]; empty for an
    /// untextured scene, whose hits then read nothing more than before.
    triangle_textures: Vec<u32>,
}

#[inline]
fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a + b > 0.0 { a / (a + b) } else { 0.0 }
}

impl<'a> Integrator<'a> {
    pub fn new(
        geometry: &'a SceneMesh,
        bvh: &'a SceneBvh,
        light: &'a EnvironmentLight<'a>,
        bounces: u32,
    ) -> Self {
        let mesh = &geometry.mesh;
        Self {
            geometry,
            bvh,
            light,
            bounces,
            offset: RAY_OFFSET_FRACTION * geometry.diagonal(),
            front_normals: (0..mesh.triangle_count())
                .map(|t| mesh.front_normal(t))
                .collect(),
            triangle_textures: if geometry.is_textured() {
                geometry.triangle_textures()
            } else {
                Vec::new()
            },
        }
    }

    /// The surface point where a ray from `origin` along `direction` hit. Either side of a
    /// triangle shows its front (CONVENTIONS.md, "Surfaces").
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        let mesh = &self.geometry.mesh;
        let corners = mesh.triangles[hit.triangle as usize];
        let weights = hit.barycentrics();
        let mut position = Vec3::ZERO;
        let mut normal = Vec3::ZERO;
        let mut albedo = Rgb::ZERO;
        for (i, w) in corners.iter().zip(weights) {
            position += mesh.positions[*i as usize] * w;
            normal += mesh.normals[*i as usize] * w;
            albedo += self.geometry.albedo[*i as usize] * w;
        }
        if let Some(&texture) = self.triangle_textures.get(hit.triangle as usize)
            && texture != NO_TEXTURE
        {
            // The texel's albedo (times the object's factor, interpolated above).
            let uv: glam::Vec2 = corners
                .iter()
                .zip(weights)
                .map(|(i, w)| mesh.uvs[*i as usize] * w)
                .sum();
            albedo *= self.geometry.textures[texture as usize].bilinear(uv);
        }
        let front = self.front_normals[hit.triangle as usize];
        SurfacePoint {
            position,
            shading_normal: normal.try_normalize().unwrap_or(front),
            front_normal: front,
            albedo,
            leaving: Skip::Triangle(hit.triangle),
        }
    }

    /// The point at vertex `v`, with rays leaving as in the bake.
    pub fn vertex(&self, v: u32) -> SurfacePoint {
        let mesh = &self.geometry.mesh;
        let normal = mesh.normals[v as usize];
        SurfacePoint {
            position: mesh.positions[v as usize],
            shading_normal: normal,
            front_normal: normal,
            // On a textured object, the texture's factor: as the bake, per unit texel value.
            albedo: self.geometry.albedo[v as usize],
            leaving: Skip::VertexTriangles(v),
        }
    }

    #[inline]
    fn origin(&self, p: &SurfacePoint) -> Vec3 {
        p.position + p.front_normal * self.offset
    }

    #[inline]
    fn trace(&self, p: &SurfacePoint, w: Vec3) -> Option<Hit> {
        self.bvh
            .closest_hit(self.origin(p), w, 0.0, f32::INFINITY, p.leaving)
    }

    #[inline]
    fn occluded(&self, p: &SurfacePoint, w: Vec3) -> bool {
        self.bvh
            .occluded(self.origin(p), w, 0.0, f32::INFINITY, p.leaving)
    }

    /// One estimate of the radiance leaving `start` (toward any direction: Lambertian), with
    /// `self.bounces` indirect bounces, and the direct visibility seen at `start`. Counts the
    /// rays traced in `rays`.
    pub fn radiance(
        &self,
        start: &SurfacePoint,
        sampler: &mut impl PathSampler,
        rays: &mut u64,
    ) -> (Rgb, DirectVisibility) {
        let mut radiance = Rgb::ZERO;
        let mut direct = DirectVisibility::default();
        let mut point = *start;
        // Albedos of every point so far: the path's throughput (cos/pdf cancels out).
        let mut throughput = point.albedo;
        for depth in 0..=self.bounces {
            let n = point.shading_normal;
            // Next-event estimation toward the environment.
            if let Some((w, pdf_light, le)) = self.light.sample_with_radiance(sampler.next_2d()) {
                let cos = n.dot(w);
                if cos > 0.0 {
                    *rays += 1;
                    let visible = !self.occluded(&point, w);
                    if depth == 0 {
                        let weight = luminance(le) * cos / pdf_light;
                        direct.unoccluded += weight;
                        if visible {
                            direct.visible += weight;
                        }
                    }
                    if visible {
                        let pdf_surface = cos * FRAC_1_PI;
                        let mis = power_heuristic(pdf_light, pdf_surface);
                        radiance += throughput * le * (cos * FRAC_1_PI / pdf_light * mis);
                    }
                }
            }
            // Cosine-weighted continuation; on escape it is the other MIS strategy for the
            // environment.
            let w = Frame::from_normal(n).to_world(cosine_hemisphere(sampler.next_2d()));
            let pdf_surface = n.dot(w).max(0.0) * FRAC_1_PI;
            // The environment seen along an escaping continuation, MIS-weighted.
            let escaped = |w: Vec3| {
                let (le, pdf_light) = self.light.radiance_and_pdf(w);
                le * power_heuristic(pdf_surface, pdf_light)
            };
            *rays += 1;
            if depth == self.bounces {
                // Only whether it escapes matters: an occlusion ray suffices.
                if !self.occluded(&point, w) {
                    radiance += throughput * escaped(w);
                }
                break;
            }
            match self.trace(&point, w) {
                None => {
                    radiance += throughput * escaped(w);
                    break;
                }
                Some(hit) => {
                    point = self.surface(&hit);
                    throughput *= point.albedo;
                }
            }
        }
        (radiance, direct)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn power_heuristic_weights_sum_to_one() {
        let (a, b) = (0.3, 2.0);
        assert!((super::power_heuristic(a, b) + super::power_heuristic(b, a) - 1.0).abs() < 1e-6);
        assert_eq!(super::power_heuristic(0.0, 0.0), 0.0);
    }
}
