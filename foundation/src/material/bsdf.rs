//! The glossy BSDF as one contract: evaluate, sample and pdf of the mixture the path tracer
//! samples (the diffuse part by the cosine, the Phong lobe around the mirror direction, chosen
//! by their reflectances' luminance).

use super::Material;
use super::lobe::{front_view, mirror, phong_lobe, sample_phong_lobe};
use crate::color::{Rgb, luminance};
use crate::sampling::{Frame, cosine_hemisphere};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// The BSDF toward one direction: `f cos` of each part and the pdf of the mixture that
/// samples it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfEval {
    pub diffuse: Rgb,
    pub specular: Rgb,
    pub pdf: f32,
}

/// A glossy point's BSDF for one view: Lambertian `albedo` plus `material`'s lobe.
#[derive(Debug, Clone, Copy)]
pub struct PhongBsdf {
    n: Vec3,
    /// The mirror direction of the view.
    mirror: Vec3,
    albedo: Rgb,
    material: Material,
    /// Probability of sampling the lobe rather than the cosine.
    lobe_probability: f32,
}

impl PhongBsdf {
    /// The BSDF at shading normal `n` seen from `wo` (unit, toward the viewer; a view from
    /// behind sees the front). `None` for a black surface (nothing to sample).
    #[inline]
    pub fn new(n: Vec3, albedo: Rgb, material: Material, wo: Vec3) -> Option<Self> {
        let (d, s) = (
            luminance(albedo).max(0.0),
            luminance(material.specular).max(0.0),
        );
        if d + s <= 0.0 {
            return None;
        }
        Some(Self {
            n,
            mirror: mirror(front_view(wo, n), n),
            albedo,
            material,
            lobe_probability: s / (d + s),
        })
    }

    /// `f cos` toward `w` and the pdf of sampling `w`.
    #[inline]
    pub fn eval(&self, w: Vec3) -> BsdfEval {
        let cos = self.n.dot(w);
        if cos <= 0.0 {
            return BsdfEval {
                diffuse: Rgb::ZERO,
                specular: Rgb::ZERO,
                pdf: 0.0,
            };
        }
        let lobe = phong_lobe(self.mirror.dot(w), self.material.shininess);
        BsdfEval {
            diffuse: self.albedo * (cos * FRAC_1_PI),
            specular: self.material.specular * lobe,
            pdf: (1.0 - self.lobe_probability) * cos * FRAC_1_PI + self.lobe_probability * lobe,
        }
    }

    /// The pdf per solid angle of [`Self::sample`]'s directions.
    #[inline]
    pub fn pdf(&self, w: Vec3) -> f32 {
        self.eval(w).pdf
    }

    /// A direction from the mixture (one 2D sample: its first coordinate also picks the part).
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let p = self.lobe_probability;
        if u.x < p {
            let u = Vec2::new((u.x / p).min(1.0 - f32::EPSILON), u.y);
            Frame::from_normal(self.mirror).to_world(sample_phong_lobe(u, self.material.shininess))
        } else {
            let u = Vec2::new(((u.x - p) / (1.0 - p)).min(1.0 - f32::EPSILON), u.y);
            Frame::from_normal(self.n).to_world(cosine_hemisphere(u))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::hammersley;

    fn bsdf(view: Vec3) -> PhongBsdf {
        let material = Material::phong(Rgb::splat(0.3), 80.0);
        PhongBsdf::new(Vec3::Z, Rgb::splat(0.5), material, view.normalize()).unwrap()
    }

    /// Sampling agrees with the pdf and the pdf with the lobes: E[f cos / pdf] over sampled
    /// directions is the reflectance, k_d + k_s for a view along the normal (whose lobe stays
    /// above the horizon); and the pdf integrates to one over the hemisphere.
    #[test]
    fn samples_follow_the_pdf_and_the_reflectance_adds_up() {
        let b = bsdf(Vec3::Z);
        let n = 256 * 256;
        let mut reflectance = 0.0f64;
        for i in 0..n {
            let w = b.sample(hammersley(i, n));
            let f = b.eval(w);
            if f.pdf > 0.0 {
                reflectance += f64::from((f.diffuse + f.specular).x / f.pdf);
            }
        }
        let reflectance = reflectance / f64::from(n);
        assert!((reflectance - 0.8).abs() < 2e-3, "{reflectance}");
        // ∫ pdf by a (cos θ, φ) midpoint rule, fine near the pole where the lobe is.
        let (nt, np) = (4000, 64);
        let mut total = 0.0f64;
        for i in 0..nt {
            let mu = (i as f32 + 0.5) / nt as f32;
            let sin = (1.0 - mu * mu).sqrt();
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                total += f64::from(b.pdf(Vec3::new(sin * phi.cos(), sin * phi.sin(), mu)));
            }
        }
        let total = total * std::f64::consts::TAU / f64::from(nt * np);
        assert!((total - 1.0).abs() < 2e-3, "{total}");
    }

    #[test]
    fn the_pdf_is_zero_below_the_surface_and_a_black_surface_has_no_bsdf() {
        let b = bsdf(Vec3::new(0.3, 0.0, 1.0));
        assert_eq!(b.pdf(-Vec3::Z), 0.0);
        assert!(b.pdf(Vec3::Z) > 0.0);
        let black = PhongBsdf::new(Vec3::Z, Rgb::ZERO, Material::DIFFUSE, Vec3::Z);
        assert!(black.is_none());
    }
}
