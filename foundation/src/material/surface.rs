//! One BSDF contract for every material that is not Lambertian (what the path tracer samples).

use super::Material;
use super::bsdf::{BsdfEval, PhongBsdf};
use super::metallic_roughness::{MetallicRoughness, MetallicRoughnessBsdf};
use crate::color::Rgb;
use glam::{Vec2, Vec3};

/// The BSDF of a point whose material is not Lambertian: a Phong lobe over its albedo, or the
/// metallic-roughness layer over its base colour. One contract for the path tracer.
#[derive(Debug, Clone, Copy)]
pub enum SurfaceBsdf {
    Phong(PhongBsdf),
    MetallicRoughness(MetallicRoughnessBsdf),
}

impl SurfaceBsdf {
    /// The BSDF at shading normal `n` seen from `wo` of a point of colour `albedo` (the base
    /// colour under a layer). `None` for a Lambertian material, or a black Phong surface.
    #[inline]
    pub fn new(n: Vec3, albedo: Rgb, material: &Material, wo: Vec3) -> Option<Self> {
        if let Some(layer) = material.layer {
            let point = MetallicRoughness {
                base_color: albedo,
                metallic: layer.metallic,
                roughness: layer.roughness,
            };
            return Some(Self::MetallicRoughness(MetallicRoughnessBsdf::new(
                n, &point, wo,
            )));
        }
        if material.is_glossy() {
            return PhongBsdf::new(n, albedo, *material, wo).map(Self::Phong);
        }
        None
    }

    /// `f cos` toward `w` and the pdf of sampling `w`.
    #[inline]
    pub fn eval(&self, w: Vec3) -> BsdfEval {
        match self {
            Self::Phong(b) => b.eval(w),
            Self::MetallicRoughness(b) => b.eval(w),
        }
    }

    /// A direction from the BSDF's mixture.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        match self {
            Self::Phong(b) => b.sample(u),
            Self::MetallicRoughness(b) => b.sample(u),
        }
    }
}
