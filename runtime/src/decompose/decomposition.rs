//! What a decomposition gives: an SH part and directional lights.

use crate::light::DirectionalLight;
use foundation::Rgb;
use foundation::sh::{ShCoeffs, clamped_cosine_bands};
use glam::Vec3;
use std::f32::consts::PI;

/// The result: SH part plus lights.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Decomposition {
    /// The polynomial part (what the PRT pass is lit by).
    pub sh: ShCoeffs<Rgb>,
    /// Lights, brightest first.
    pub lights: Vec<DirectionalLight>,
    /// `∫ L dω` of the map.
    pub total_power: Rgb,
    /// Peaks that passed the contrast test (before the Weber elbow).
    pub candidates: usize,
}

impl Decomposition {
    /// Unshadowed Lambertian irradiance of SH part plus lights for unit normal `n`.
    pub fn irradiance(&self, n: Vec3) -> Rgb {
        let mut sh = self.sh.clone();
        sh.scale_bands(&clamped_cosine_bands(sh.order()));
        let lights: Rgb = self.lights.iter().map(|l| l.irradiance(n)).sum();
        sh.eval(n) + lights
    }

    /// `∫` of SH part plus lights over the sphere.
    pub fn total(&self) -> Rgb {
        self.sh.as_slice()[0] * (4.0 * PI).sqrt() + self.lights.iter().map(|l| l.power).sum::<Rgb>()
    }
}
