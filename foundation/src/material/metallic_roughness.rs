//! The glTF 2.0 metallic-roughness BRDF (the specification's Appendix B): a Lambertian base
//! under a GGX (Trowbridge–Reitz) specular layer, Smith height-correlated visibility and
//! Schlick's Fresnel, metals and dielectrics mixed by `metallic`:
//!
//! `f = (1 − F) c_diff / π + F D V`, with `c_diff = (1 − metallic) base`,
//! `F = F₀ + (1 − F₀)(1 − |v·h|)⁵`, `F₀ = lerp(0.04, base, metallic)`, `α = roughness²`,
//! `D = α² / (π ((n·h)²(α² − 1) + 1)²)` and
//! `V = 1 / (2 (n·l √((n·v)²(1 − α²) + α²) + n·v √((n·l)²(1 − α²) + α²)))`.
//!
//! Sampled as a mixture: the cosine for the diffuse part, visible normals for the specular
//! one (Heitz 2018, "Sampling the GGX Distribution of Visible Normals"), each picked by an
//! estimate of its share of the reflected light.

use super::BsdfEval;
use crate::color::{Rgb, luminance};
use crate::sampling::{Frame, cosine_hemisphere};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI, TAU};

/// Reflectance at normal incidence of the dielectric the specification assumes (IOR 1.5).
pub const DIELECTRIC_F0: f32 = 0.04;

/// Smallest `α` the GGX terms are evaluated at: a perfect mirror has no density to sample
/// against a map, and `α = 0` divides by zero.
pub const MIN_ALPHA: f32 = 1e-3;

/// A glTF material's parameters at one point (factors times textures, already clamped).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MetallicRoughness {
    /// Linear base colour.
    pub base_color: Rgb,
    /// 0 (dielectric) to 1 (metal).
    pub metallic: f32,
    /// Perceptual roughness, 0 to 1 (`α = roughness²`).
    pub roughness: f32,
}

impl MetallicRoughness {
    /// The diffuse colour and the reflectance at normal incidence.
    pub fn diffuse_and_f0(&self) -> (Rgb, Rgb) {
        let m = self.metallic;
        let diffuse = self.base_color * (1.0 - m);
        let f0 = Rgb::splat(DIELECTRIC_F0) * (1.0 - m) + self.base_color * m;
        (diffuse, f0)
    }

    /// GGX's `α` (perceptual roughness squared), at least [`MIN_ALPHA`].
    pub fn alpha(&self) -> f32 {
        (self.roughness * self.roughness).max(MIN_ALPHA)
    }
}

/// The GGX normal distribution `D(h)` for `cos_h = n·h`.
#[inline]
pub fn ggx_distribution(cos_h: f32, alpha: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = cos_h * cos_h * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Smith's height-correlated visibility `V = G₂ / (4 n·l n·v)` for cosines above zero.
#[inline]
pub fn smith_visibility(cos_l: f32, cos_v: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = cos_l * (cos_v * cos_v * (1.0 - a2) + a2).sqrt();
    let gl = cos_v * (cos_l * cos_l * (1.0 - a2) + a2).sqrt();
    let sum = gv + gl;
    if sum > 0.0 { 0.5 / sum } else { 0.0 }
}

/// Smith's masking `G₁(v)` of GGX, for `cos_v = n·v > 0`.
#[inline]
pub fn smith_masking(cos_v: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    2.0 * cos_v / (cos_v + (a2 + (1.0 - a2) * cos_v * cos_v).sqrt())
}

/// Schlick's Fresnel for `cos = v·h`.
#[inline]
pub fn schlick_fresnel(f0: Rgb, cos: f32) -> Rgb {
    let k = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Rgb::ONE - f0) * k
}

/// A visible normal of GGX for the view `v` in the local frame (+Z the normal, `v.z > 0`),
/// from a 2D sample (Heitz 2018, listing 1, isotropic).
#[inline]
pub fn sample_visible_normal(v: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    // The view in the hemisphere configuration (the distribution stretched to α = 1).
    let vh = Vec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    // A point of the projected disk, its lower half squeezed by the view's slant.
    let r = u.x.sqrt();
    let phi = TAU * u.y;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// One point's metallic-roughness BSDF for one view, in the contract of
/// [`super::PhongBsdf`]: `f cos` of each part toward a direction, the mixture's pdf, samples.
#[derive(Debug, Clone, Copy)]
pub struct MetallicRoughnessBsdf {
    frame: Frame,
    /// The view in the local frame (+Z the normal; a view from behind sees the front).
    wo: Vec3,
    diffuse: Rgb,
    f0: Rgb,
    alpha: f32,
    /// Probability of sampling the specular layer rather than the cosine.
    specular_probability: f32,
}

impl MetallicRoughnessBsdf {
    /// The BSDF at shading normal `n` seen from `wo` (unit, toward the viewer). Never black:
    /// even a black metal reflects at grazing angles (Schlick's Fresnel).
    pub fn new(n: Vec3, material: &MetallicRoughness, wo: Vec3) -> Self {
        let frame = Frame::from_normal(n);
        let local = frame.to_local(wo);
        let local = Vec3::new(local.x, local.y, local.z.abs().max(1e-4)).normalize();
        let (diffuse, f0) = material.diffuse_and_f0();
        // Shares of the reflected light, roughly: the layer's Fresnel at the view (kept above
        // zero: microfacets tilted from the view reflect even where `F₀` is 0), the base what
        // the layer lets through.
        let fresnel = luminance(schlick_fresnel(f0, local.z)).max(0.01);
        let base = luminance(diffuse).max(0.0) * (1.0 - fresnel);
        Self {
            frame,
            wo: local,
            diffuse,
            f0,
            alpha: material.alpha(),
            specular_probability: fresnel / (fresnel + base),
        }
    }

    /// `f cos` toward `w` (unit, world) of the diffuse and specular parts, and the pdf of
    /// sampling `w`.
    pub fn eval(&self, w: Vec3) -> BsdfEval {
        let l = self.frame.to_local(w);
        if l.z <= 0.0 {
            return BsdfEval {
                diffuse: Rgb::ZERO,
                specular: Rgb::ZERO,
                pdf: 0.0,
            };
        }
        let v = self.wo;
        let h = (v + l).normalize();
        let fresnel = schlick_fresnel(self.f0, v.dot(h));
        let d = ggx_distribution(h.z, self.alpha);
        let vis = smith_visibility(l.z, v.z, self.alpha);
        let specular_pdf = self.visible_normal_pdf(h, v);
        let p = self.specular_probability;
        BsdfEval {
            diffuse: (Rgb::ONE - fresnel) * self.diffuse * (l.z * FRAC_1_PI),
            specular: fresnel * (d * vis * l.z),
            pdf: (1.0 - p) * l.z * FRAC_1_PI + p * specular_pdf,
        }
    }

    /// The pdf per solid angle of the reflected direction when `h` is a sampled visible
    /// normal: `G₁(v) max(0, v·h) D(h) / (n·v) / (4 v·h)`.
    fn visible_normal_pdf(&self, h: Vec3, v: Vec3) -> f32 {
        let vh = v.dot(h);
        if vh <= 0.0 {
            return 0.0;
        }
        smith_masking(v.z, self.alpha) * ggx_distribution(h.z, self.alpha) / (4.0 * v.z)
    }

    /// The pdf per solid angle of [`Self::sample`]'s directions.
    pub fn pdf(&self, w: Vec3) -> f32 {
        self.eval(w).pdf
    }

    /// A direction from the mixture (one 2D sample: its first coordinate also picks the
    /// part); it may lie below the surface (a reflection off a slanted microfacet), where
    /// the BSDF is zero.
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let p = self.specular_probability;
        if u.x < p {
            let u = Vec2::new((u.x / p).min(1.0 - f32::EPSILON), u.y);
            let h = sample_visible_normal(self.wo, self.alpha, u);
            let l = 2.0 * self.wo.dot(h) * h - self.wo;
            self.frame.to_world(l)
        } else {
            let u = Vec2::new(((u.x - p) / (1.0 - p)).min(1.0 - f32::EPSILON), u.y);
            self.frame.to_world(cosine_hemisphere(u))
        }
    }
}

/// The split-sum terms of the specular layer's directional albedo for a view at
/// `cos_v = n·v`: `E = F₀ A + B` (Schlick's Fresnel is linear in `F₀`). What a renderer
/// scales its prefiltered reflections by (Karis 2013; Filament's DFG). Estimated by
/// sampling visible normals, whose weight is `G₂ / G₁(v)` whatever the normal drawn.
pub fn split_sum_terms(cos_v: f32, roughness: f32, samples: u32) -> (f32, f32) {
    let alpha = (roughness * roughness).max(MIN_ALPHA);
    let cos_v = cos_v.clamp(1e-4, 1.0);
    let v = Vec3::new((1.0 - cos_v * cos_v).sqrt(), 0.0, cos_v);
    let g1 = smith_masking(cos_v, alpha);
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for i in 0..samples {
        let h = sample_visible_normal(v, alpha, crate::sampling::hammersley(i, samples));
        let vh = v.dot(h);
        let l = 2.0 * vh * h - v;
        if l.z <= 0.0 || vh <= 0.0 {
            continue;
        }
        let g2 = 4.0 * smith_visibility(l.z, cos_v, alpha) * l.z * cos_v;
        let weight = f64::from(g2 / g1);
        let fc = f64::from((1.0 - vh).powi(5));
        a += weight * (1.0 - fc);
        b += weight * fc;
    }
    let n = f64::from(samples.max(1));
    ((a / n) as f32, (b / n) as f32)
}

/// [`split_sum_terms`] averaged over views, cosine-weighted (`2 ∫ (A, B)(μ) μ dμ`): the
/// layer's hemispherical albedo is `F₀ A + B`. What a layered surface reflects toward other
/// surfaces in the bake, where its direction is not kept (CONVENTIONS.md, "Metallic-roughness
/// materials").
pub fn hemispherical_split_sum(roughness: f32, views: u32, samples: u32) -> (f32, f32) {
    let views = views.max(1);
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for i in 0..views {
        let mu = (i as f32 + 0.5) / views as f32;
        let (ai, bi) = split_sum_terms(mu, roughness, samples);
        a += f64::from(ai * mu);
        b += f64::from(bi * mu);
    }
    let scale = 2.0 / f64::from(views);
    ((a * scale) as f32, (b * scale) as f32)
}

/// The Phong exponent whose normalised lobe around the mirror direction has the peak of the
/// layer's reflected GGX lobe seen along the normal, `D(n)/4 = 1/(4πα²)` per solid angle
/// against Phong's `(s + 1)/(2π)`: the two cores are then nearly the same Gaussian (GGX's
/// tails are heavier). What the renderer prefilters the layer's reflection map with (at
/// least 1: rougher layers are about as wide as a cosine).
pub fn equivalent_shininess(roughness: f32) -> f32 {
    let alpha = (roughness * roughness).max(MIN_ALPHA);
    (0.5 / (alpha * alpha) - 1.0).clamp(1.0, super::MAX_SHININESS)
}

/// [`split_sum_terms`] tabulated over `n·v` (columns) and roughness (rows), both from 0 to
/// 1 at the texel centres, read back bilinearly: the table a GPU pass samples.
#[derive(Debug, Clone, PartialEq)]
pub struct SplitSumTable {
    size: usize,
    /// `(A, B)` per texel, row by row.
    terms: Vec<[f32; 2]>,
}

impl SplitSumTable {
    /// A `size × size` table, each texel from `samples` visible normals.
    pub fn new(size: usize, samples: u32) -> Self {
        let size = size.max(2);
        let centre = |k: usize| (k as f32 + 0.5) / size as f32;
        let terms = (0..size * size)
            .map(|i| {
                let (a, b) = split_sum_terms(centre(i % size), centre(i / size), samples);
                [a, b]
            })
            .collect();
        Self { size, terms }
    }

    /// `(A, B)` of texel `i` (n·v) in row `j` (roughness).
    pub fn texel(&self, i: usize, j: usize) -> [f32; 2] {
        self.terms[j.min(self.size - 1) * self.size + i.min(self.size - 1)]
    }

    /// `(A, B)` at `cos_v` and `roughness`, bilinear between texel centres (clamped at the
    /// edges).
    pub fn lookup(&self, cos_v: f32, roughness: f32) -> (f32, f32) {
        let n = self.size;
        let coordinate = |x: f32| {
            let p = (x.clamp(0.0, 1.0) * n as f32 - 0.5).clamp(0.0, (n - 1) as f32);
            let k = (p.floor() as usize).min(n - 2);
            (k, p - k as f32)
        };
        let ((i, fx), (j, fy)) = (coordinate(cos_v), coordinate(roughness));
        let at = |i: usize, j: usize| self.terms[j * n + i];
        let mix =
            |a: [f32; 2], b: [f32; 2], t: f32| [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
        let top = mix(at(i, j), at(i + 1, j), fx);
        let bottom = mix(at(i, j + 1), at(i + 1, j + 1), fx);
        let [a, b] = mix(top, bottom, fy);
        (a, b)
    }
}

#[cfg(test)]
mod tests;
