//! Surface materials: Lambertian diffuse plus an optional normalised Phong lobe
//! (CONVENTIONS.md, "Glossy materials"), or glTF's metallic-roughness layer over a base colour
//! ([`metallic_roughness`]).
//!
//! `f(ω_i, ω_o) = k_d/π + k_s (s + 1)/(2π) cos^s α / (n·ω_i)`, with `α` the angle between the
//! incident direction and the mirror direction `r` of the view, for `n·ω_i > 0`. Dividing the
//! lobe by the cosine makes the reflected radiance `k_d E(n)/π + k_s (D_s ∗ L)(r)`: the map
//! convolved with the normalised lobe `D_s(α) = (s + 1)/(2π) cos^s α` around `r` (exact
//! except where the lobe crosses the horizon), so a prefiltered reflection map is exact and a
//! directional light of power `P` adds `k_s P D_s(α)`.
//!
//! Every consumer (the path tracer, the GPU passes, the SH baseline, the Mitsuba plugin) uses
//! these functions or their WGSL/Python transcriptions.

mod bsdf;
mod lobe;
pub mod metallic_roughness;
mod surface;

pub use bsdf::{BsdfEval, PhongBsdf};
pub use surface::SurfaceBsdf;

pub use lobe::{mirror, phong_lobe, phong_zonal};

use crate::color::Rgb;

/// Largest shininess a scene may give (a lobe about 0.6° wide).
pub const MAX_SHININESS: f32 = 10_000.0;

/// What a surface does beyond the colour that lives with the geometry (the albedo, or the
/// base colour under a metallic-roughness layer).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Material {
    /// `k_s` per channel; zero for a purely diffuse surface (and under a `layer`).
    pub specular: Rgb,
    /// Phong exponent `s` (meaningless when `specular` is zero).
    pub shininess: f32,
    /// glTF's metallic-roughness layer: the geometry's colour is then its base colour, and
    /// there is no Phong lobe.
    pub layer: Option<Layer>,
}

/// The metallic-roughness factors of a surface ([`metallic_roughness::MetallicRoughness`]
/// with its base colour), each in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Layer {
    pub metallic: f32,
    pub roughness: f32,
}

impl Material {
    /// Lambertian only.
    pub const DIFFUSE: Material = Material {
        specular: Rgb::ZERO,
        shininess: 0.0,
        layer: None,
    };

    /// A Phong lobe over the Lambertian albedo.
    pub const fn phong(specular: Rgb, shininess: f32) -> Material {
        Material {
            specular,
            shininess,
            layer: None,
        }
    }

    /// glTF's metallic-roughness material over the base colour.
    pub const fn metallic_roughness(metallic: f32, roughness: f32) -> Material {
        Material {
            specular: Rgb::ZERO,
            shininess: 0.0,
            layer: Some(Layer {
                metallic,
                roughness,
            }),
        }
    }

    /// Whether it has a Phong lobe.
    pub fn is_glossy(&self) -> bool {
        self.specular.max_element() > 0.0
    }

    /// Whether anything about it depends on the view (a Phong lobe or a layer).
    pub fn is_lambertian(&self) -> bool {
        !self.is_glossy() && self.layer.is_none()
    }
}

impl Default for Material {
    fn default() -> Self {
        Self::DIFFUSE
    }
}

/// A material whose reflectances add up to more than one in some channel.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "albedo + specular is {:.3?}: it must be at most 1 per channel (energy conservation)",
    sum.to_array()
)]
pub(crate) struct EnergyError {
    pub sum: Rgb,
}

/// `k_d + k_s ≤ 1` per channel (energy conservation).
pub(crate) fn check_energy(albedo: Rgb, specular: Rgb) -> Result<(), EnergyError> {
    let sum = albedo + specular;
    if sum.max_element() > 1.0 + 1e-6 {
        return Err(EnergyError { sum });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_is_checked() {
        assert!(check_energy(Rgb::splat(0.5), Rgb::splat(0.5)).is_ok());
        assert!(check_energy(Rgb::new(0.5, 0.7, 0.1), Rgb::splat(0.4)).is_err());
    }
}
