//! "SH + one sun", common game-engine practice: the strongest source of the map becomes one
//! shadow-mapped light carrying its cap's energy, and the rest is order-3 SH irradiance
//! (bands 0–2) applied per pixel by the surface normal, unshadowed: no transfer, no
//! interreflection (`shaders/geometry.wgsl`).
//!
//! The light and the remainder come from the consistent decomposition limited to one light
//! (the brightest peak, whatever its Weber ratio), so the light's power and the SH part add up
//! to the map; the SH part is then cut to order 3.

use crate::decompose::{DecomposeMode, DecomposeSettings};

/// Order of the SH irradiance (bands 0–2).
pub(crate) const SH_ORDER: usize = 3;

/// The decomposition that finds the sun: consistent mode, one light, no Weber cut-off; the
/// analysis (cube size, icosphere, smoothing) and order of `base`.
pub(crate) fn settings(base: &DecomposeSettings) -> DecomposeSettings {
    DecomposeSettings {
        max_lights: 1,
        threshold: 0.0,
        face_size: base.face_size,
        ico_level: base.ico_level,
        smoothing_deg: base.smoothing_deg,
        ..DecomposeSettings::for_mode(DecomposeMode::Consistent, base.order)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::envmap::EnvMap;
    use foundation::{Rgb, luminance};
    use glam::Vec3;
    use std::f32::consts::PI;

    /// Under a sky `L(ω) = 1 + ω_y` (exactly bands 0 and 1), a surface of normal n receives
    /// `E(n) = π + (2π/3) n_y`; the transfer gives ρ/π of that.
    /// A 2° sun over a sky: the one light sits on the sun, carries its power, turns with the
    /// map, and the rest is order-3 SH applied unshadowed, adding up to the map.
    #[test]
    fn the_light_is_on_the_disc_and_carries_it() {
        use crate::lighting::{EnvironmentLighting, RenderMode, ShTransfer};
        let sun = Vec3::new(-0.4, 0.7, 0.5).normalize();
        let radius = 2f32.to_radians();
        let (sky, disc) = (0.4, 300.0);
        let map = EnvMap::from_fn(512, 256, 4, |w| {
            Rgb::splat(if w.dot(sun) >= radius.cos() {
                disc
            } else {
                sky * (1.2 + w.y)
            })
        });
        let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default()).unwrap();
        let frame = lighting.frame(RenderMode::ShSun, None).lighting;
        assert_eq!(frame.lights.len(), 1);
        assert_eq!(frame.sh.order(), SH_ORDER);
        assert_eq!(frame.sh_transfer, ShTransfer::Unshadowed);
        assert!(!frame.lights_indirect);
        let light = frame.lights[0];
        assert!(light.direction.angle_between(sun) < 0.5f32.to_radians());
        let sun_power = (disc - sky * (1.2 + sun.y)) * 2.0 * PI * (1.0 - radius.cos());
        let power = luminance(light.power);
        assert!(
            (power - sun_power).abs() < 0.05 * sun_power,
            "{power} vs {sun_power}"
        );
        lighting.set_rotation(90.0);
        let turned = lighting.frame(RenderMode::ShSun, None).lighting.lights[0];
        let expected = glam::Quat::from_rotation_y(90f32.to_radians()) * sun;
        assert!(turned.direction.angle_between(expected) < 0.5f32.to_radians());
    }
}
