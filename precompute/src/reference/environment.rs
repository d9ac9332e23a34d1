//! The environment as a light source for the path tracer: radiance lookup and importance
//! sampling in world space, with the map's rotation about +Y.

use crate::color::Rgb;
use crate::envmap::sampling::EnvSampler;
use crate::envmap::{EnvMap, rotate_y};
use glam::{Vec2, Vec3};

/// Distant lighting `L(ω) = map(R_y(−rotation) ω)` (CONVENTIONS.md, "Rotating an environment").
pub struct EnvironmentLight<'a> {
    map: &'a EnvMap,
    sampler: Option<EnvSampler>,
    rotation: f32,
}

impl<'a> EnvironmentLight<'a> {
    /// `rotation_deg` turns the map about +Y, counter-clockwise seen from above.
    pub fn new(map: &'a EnvMap, rotation_deg: f32) -> Self {
        Self {
            map,
            sampler: EnvSampler::new(map),
            rotation: rotation_deg.to_radians(),
        }
    }

    pub fn map(&self) -> &EnvMap {
        self.map
    }

    /// Radiance arriving from world direction `w`.
    #[inline]
    pub fn radiance(&self, w: Vec3) -> Rgb {
        self.map.radiance(rotate_y(w, -self.rotation))
    }

    /// A world direction drawn proportionally to luminance × solid angle, with its density;
    /// `None` for a black environment.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let (w, pdf) = self.sampler.as_ref()?.sample(u);
        (pdf > 0.0).then(|| (rotate_y(w, self.rotation), pdf))
    }

    /// Density of [`Self::sample`] producing world direction `w`.
    #[inline]
    pub fn pdf(&self, w: Vec3) -> f32 {
        self.sampler
            .as_ref()
            .map_or(0.0, |s| s.pdf(rotate_y(w, -self.rotation)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_applies_to_lookup_and_sampling() {
        let map = EnvMap::from_fn(64, 32, 1, |w| {
            if w.z < -0.95 {
                Rgb::splat(100.0)
            } else {
                Rgb::splat(0.1)
            }
        });
        let light = EnvironmentLight::new(&map, 90.0);
        // The bright spot toward -Z moved to -X.
        assert_eq!(light.radiance(Vec3::NEG_X), Rgb::splat(100.0));
        assert_eq!(light.radiance(Vec3::NEG_Z), Rgb::splat(0.1));
        let (w, pdf) = light.sample(Vec2::new(0.5, 0.5)).unwrap();
        assert!((pdf - light.pdf(w)).abs() < 1e-3 * pdf);
    }
}
