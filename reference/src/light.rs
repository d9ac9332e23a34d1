//! The environment as a light source for the path tracer: radiance lookup and importance
//! sampling in world space, with the map's rotation about +Y.

use foundation::color::Rgb;
use foundation::envmap::sampling::EnvSampler;
use foundation::envmap::{EnvMap, YRotation};
use foundation::infra::huge_pages::HugePageTable;
use glam::{Vec2, Vec3, Vec4};

/// Distant lighting `L(ω) = map(R_y(−rotation) ω)` (CONVENTIONS.md, "Rotating an environment").
pub struct EnvironmentLight<'a> {
    map: &'a EnvMap,
    sampler: Option<EnvSampler>,
    /// Per texel: its radiance and its sampling density times `sin θ`, side by side, so a
    /// path escaping the scene reads one cache line for both.
    texels: HugePageTable<Vec4>,
    /// The map's rotation (map to world) and its inverse (world to map), each with its sine
    /// and cosine computed once.
    to_world: YRotation,
    to_map: YRotation,
}

/// A texel of the map chosen ahead of its use (see [`EnvironmentLight::sample_texel`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PendingTexel {
    index: usize,
    /// Sine of the polar angle of the direction it was chosen for.
    sin_theta: f32,
}

impl<'a> EnvironmentLight<'a> {
    /// `rotation_deg` turns the map about +Y, counter-clockwise seen from above.
    pub fn new(map: &'a EnvMap, rotation_deg: f32) -> Self {
        let sampler = EnvSampler::new(map);
        let texels = HugePageTable::new(map.texels().iter().enumerate().map(|(k, l)| {
            let factor = sampler.as_ref().map_or(0.0, |s| s.texel_density_factor(k));
            Vec4::new(l.x, l.y, l.z, factor)
        }));
        Self {
            map,
            sampler,
            texels,
            to_world: YRotation::new(rotation_deg.to_radians()),
            to_map: YRotation::new(-rotation_deg.to_radians()),
        }
    }

    pub fn map(&self) -> &EnvMap {
        self.map
    }

    /// Radiance arriving from world direction `w`.
    #[inline]
    pub fn radiance(&self, w: Vec3) -> Rgb {
        self.map.radiance(self.to_map.apply(w))
    }

    /// A world direction drawn proportionally to luminance × solid angle, with its density;
    /// `None` for a black environment.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        self.sample_with_radiance(u).map(|(w, pdf, _)| (w, pdf))
    }

    /// [`Self::sample`] with the radiance arriving from the direction drawn (one lookup).
    #[inline]
    pub(crate) fn sample_with_radiance(&self, u: Vec2) -> Option<(Vec3, f32, Rgb)> {
        let (w, texel) = self.sample_texel(u)?;
        let (radiance, pdf) = self.texel_value(texel);
        (pdf > 0.0).then_some((w, pdf, radiance))
    }

    /// A world direction drawn as by [`Self::sample`], with its texel: asked of the cache
    /// now, read by [`Self::texel_value`] once the shadow ray has decided whether it counts,
    /// so that the read waits on memory while the ray is traced.
    #[inline]
    pub(crate) fn sample_texel(&self, u: Vec2) -> Option<(Vec3, PendingTexel)> {
        let (w, sin_theta, index) = self.sampler.as_ref()?.locate(u);
        Some((self.to_world.apply(w), self.pending(index, sin_theta)))
    }

    /// The texel a path escaping along world direction `w` sees, asked of the cache now (as
    /// [`Self::sample_texel`]): computed before the ray that finds out whether it escapes.
    #[inline]
    pub(crate) fn escape_texel(&self, w: Vec3) -> PendingTexel {
        let local = self.to_map.apply(w);
        let (i, j) = self.map.texel_of(local);
        // From x and z, which keep their precision near the poles (unlike 1 − y²).
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        self.pending(j * self.map.width() + i, sin_theta)
    }

    #[inline]
    fn pending(&self, index: usize, sin_theta: f32) -> PendingTexel {
        foundation::infra::prefetch::prefetch(self.texels.as_ptr().wrapping_add(index));
        PendingTexel { index, sin_theta }
    }

    /// The texel's radiance and the solid-angle density of sampling its direction.
    #[inline]
    pub(crate) fn texel_value(&self, texel: PendingTexel) -> (Rgb, f32) {
        let value = self.texels[texel.index];
        let pdf = if texel.sin_theta > 0.0 {
            value.w / texel.sin_theta
        } else {
            0.0
        };
        (value.truncate(), pdf)
    }

    /// The radiance arriving from world direction `w` and the density of sampling it (one
    /// lookup for both: what a path escaping along `w` needs).
    #[inline]
    #[cfg(test)]
    pub(crate) fn radiance_and_pdf(&self, w: Vec3) -> (Rgb, f32) {
        self.texel_value(self.escape_texel(w))
    }

    /// Density of [`Self::sample`] producing world direction `w`.
    #[inline]
    pub fn pdf(&self, w: Vec3) -> f32 {
        self.sampler
            .as_ref()
            .map_or(0.0, |s| s.pdf(self.to_map.apply(w)))
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
        // The one-lookup forms agree with the separate ones.
        for u in [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.7, 0.55),
            Vec2::new(0.93, 0.9),
        ] {
            let (w, pdf, radiance) = light.sample_with_radiance(u).unwrap();
            assert_eq!(radiance, light.radiance(w));
            let (escaped, escaped_pdf) = light.radiance_and_pdf(w);
            assert_eq!(escaped, radiance);
            assert!((escaped_pdf - light.pdf(w)).abs() < 1e-6 * escaped_pdf);
            assert!((pdf - light.pdf(w)).abs() < 1e-3 * pdf);
        }
    }
}
