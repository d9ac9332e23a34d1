//! Directional lights: what the decomposition hands the shadow-mapped passes.

use foundation::Rgb;
use glam::Vec3;

/// A distant light standing for a concentrated source of the environment map.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DirectionalLight {
    /// Unit direction the light arrives from.
    pub direction: Vec3,
    /// RGB power: `∫ L dω` over the source, i.e. the irradiance on a surface facing it.
    pub power: Rgb,
    /// Radius of the cap (the SRBF support) the light was taken from, in radians.
    pub cap_radius: f32,
    /// Estimated angular radius of the source itself, in radians (sizes soft shadows).
    pub angular_radius: f32,
    /// Angular radius of the disc standing for the glow or halo around the source, radians
    /// (equal to `angular_radius` where it has none).
    pub halo_radius: f32,
    /// Fraction of the power from the source itself, the rest from its halo (1: none).
    pub core_fraction: f32,
    /// Share of the map's total luminous power.
    pub share: f32,
}

impl DirectionalLight {
    /// Irradiance on a surface with unit normal `n` (no shadowing).
    pub fn irradiance(&self, n: Vec3) -> Rgb {
        self.power * n.dot(self.direction).max(0.0)
    }
}
