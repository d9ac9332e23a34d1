//! What glossy surfaces reflect besides the directional lights (CONVENTIONS.md, "Glossy
//! materials"): the environment convolved with the normalised Phong lobe, looked up at the
//! mirror direction. Two sources, by render mode:
//!
//! - [`ReflectedEnvironment::Remainder`]: the map minus what the lights carry (inside each
//!   light's cap the map is clipped to the SH part, `min(L, P)`: exactly what the consistent
//!   decomposition leaves after taking the excess `max(0, L − P)` as the light), as a cube map
//!   the GPU prefilters per shininess ([`crate::render::reflection_maps`]);
//! - [`ReflectedEnvironment::Sh`]: an SH polynomial convolved with the lobe's zonal factors
//!   (`λ_l L_lm`, [`phong_zonal`]): plain PRT's baseline, and the "SH + sun" peer's.

use crate::cubemap::{CubeGeometry, CubeMap};
use crate::light::DirectionalLight;
use foundation::Rgb;
use foundation::material::phong_zonal;
use foundation::sh::ShCoeffs;
use glam::Quat;
use std::sync::Arc;

/// A cube map shared between frames; frames compare it by identity (it is rebuilt, not
/// edited, when the lighting changes).
#[derive(Debug, Clone)]
pub struct SharedCube(pub Arc<CubeMap>);

impl PartialEq for SharedCube {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The environment glossy surfaces reflect, apart from the lights' own lobes.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum ReflectedEnvironment {
    /// Nothing (the lights alone).
    #[default]
    None,
    /// An SH polynomial, in world space, convolved per shininess by its zonal factors.
    Sh(ShCoeffs<Rgb>),
    /// The remainder of the map in the map's own frame, prefiltered per shininess, looked up
    /// turned by `orientation` (map frame → world), so a turning map needs no new
    /// prefiltering.
    Remainder { cube: SharedCube, orientation: Quat },
}

/// The map with the lights' share removed: inside the cap of each light (`cap_radius` around
/// its direction) each channel is clipped to the SH part `sh`, elsewhere the map is kept.
/// `map`, `sh` and the lights are in the same frame.
pub(crate) fn remainder_cube(
    map: &CubeMap,
    geometry: &CubeGeometry,
    sh: &ShCoeffs<Rgb>,
    lights: &[DirectionalLight],
) -> CubeMap {
    let mut out = map.clone();
    let mut cap = Vec::new();
    let mut seen = vec![false; geometry.texel_count()];
    for light in lights {
        geometry.texels_within(light.direction, light.cap_radius, &mut cap);
        for &t in &cap {
            let t = t as usize;
            if std::mem::replace(&mut seen[t], true) {
                continue;
            }
            let p = sh.eval(geometry.directions()[t]).max(Rgb::ZERO);
            out.texels_mut()[t] = map.texels()[t].min(p);
        }
    }
    out
}

/// `sh` convolved with the normalised lobe of `shininess`, evaluated at every texel of
/// `geometry`: the prefiltered reflection map of an SH environment.
pub(crate) fn sh_reflection_map(
    sh: &ShCoeffs<Rgb>,
    shininess: f32,
    geometry: &CubeGeometry,
) -> CubeMap {
    let mut convolved = sh.clone();
    convolved.scale_bands(&phong_zonal(shininess, sh.order()));
    CubeMap::from_fn(geometry, |w| convolved.eval(w))
}

/// The reference convolution: `∫ D_s(r·ω) L(ω) dω` over every texel of `map` (slow; for
/// tests and for measuring the GPU's quadrature).
pub fn convolve_exact(
    map: &CubeMap,
    geometry: &CubeGeometry,
    shininess: f32,
    r: glam::Vec3,
) -> Rgb {
    let mut sum = Rgb::ZERO;
    let mut weight = 0.0;
    for ((l, d), a) in map
        .texels()
        .iter()
        .zip(geometry.directions())
        .zip(geometry.solid_angles())
    {
        let w = foundation::material::phong_lobe(r.dot(*d), shininess) * a;
        sum += *l * w;
        weight += w;
    }
    if weight > 0.0 {
        sum / weight
    } else {
        Rgb::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn remainder_clips_only_inside_the_caps() {
        let geometry = CubeGeometry::new(16);
        let sun = Vec3::new(0.3, 0.8, 0.2).normalize();
        let map = CubeMap::from_fn(&geometry, |w| {
            Rgb::splat(if w.dot(sun) > 0.99 { 50.0 } else { 1.0 })
        });
        let mut sh = ShCoeffs::zeros(3);
        // A constant SH part of 2: the sun is clipped to 2, the rest (1) is kept.
        sh.as_mut_slice()[0] = Rgb::splat(2.0 / 0.282_094_8);
        let light = DirectionalLight {
            direction: sun,
            power: Rgb::ONE,
            cap_radius: 0.3,
            angular_radius: 0.1,
            halo_radius: 0.1,
            core_fraction: 1.0,
            share: 0.0,
        };
        let out = remainder_cube(&map, &geometry, &sh, &[light]);
        for (t, d) in geometry.directions().iter().enumerate() {
            let want = if d.dot(sun) > 0.99 { 2.0 } else { 1.0 };
            assert!(
                (out.texels()[t].x - want).abs() < 1e-4,
                "{t}: {}",
                out.texels()[t]
            );
        }
        // Without lights the map is unchanged.
        assert_eq!(remainder_cube(&map, &geometry, &sh, &[]), map);
    }

    #[test]
    fn sh_reflection_of_a_linear_sky_matches_the_exact_convolution() {
        // L(ω) = 1 + ω·a is band-limited to l ≤ 1, so its SH convolution is exact.
        let geometry = CubeGeometry::new(32);
        let a = Vec3::new(0.2, 0.6, -0.3);
        let map = CubeMap::from_fn(&geometry, |w| Rgb::splat(1.0 + w.dot(a)));
        let mut sh = ShCoeffs::zeros(3);
        for ((l, d), w) in map
            .texels()
            .iter()
            .zip(geometry.directions())
            .zip(geometry.solid_angles())
        {
            sh.add_delta(*d, *l * *w);
        }
        let s = 8.0;
        let reflection = sh_reflection_map(&sh, s, &geometry);
        for t in (0..geometry.texel_count()).step_by(97) {
            let r = geometry.directions()[t];
            let exact = convolve_exact(&map, &geometry, s, r);
            assert!(
                (reflection.texels()[t].x - exact.x).abs() < 0.01,
                "{r}: {} vs {}",
                reflection.texels()[t].x,
                exact.x
            );
        }
    }
}
